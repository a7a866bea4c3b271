"""The stop express: a STOP's frame written to the controller by a process of its own.

Every thread of the bridge's process shares one interpreter lock. A stop read by the stop lane
(lane.py) still waits for that lock at each step (the lane's paho thread, the last word, the
mailbox, the serial-lines thread) while anything else holds it: the main connection reading a
backlog of targets, the console, a tracking starting. Bounds and courtesies (lane.py rule 4,
the front ends' budgets) keep those waits short, not absent. So the stop's frame takes a
second path that no work of the bridge's process can hold up: a small child process with its
own interpreter, its own connection to the broker and a copy of each port's descriptor. The
bridge itself is unchanged: the same stop reaches it on the stop lane and the main connection,
and its session decides and writes as before; the express only gets the frame to the wire
first. Both halves live here: ``Express`` in the bridge, ``main`` in the child.

Rules:
1. A process of its own (``python -m bridge.mqtt.express``), started by ``Express.start`` once
   the main connection is up (as the lane: the broker is known to take the bridge), on a
   thread of its own that then stays to read the child's words (one thread, asleep on a
   socket). The child imports paho, connection.py, the settings and payloads.py (the words
   of a lock ON), nothing of the engine.
2. Its connection is the lane's in all but the client id (``express_client_id``): the same
   broker settings, credentials and TLS (the password handed over the control socket, never
   on the command line), the protocol the main connection settled on, subscribed to the stop
   and lock topics only and without the broker's replay of a retained message (lastword.py
   rule 6). It publishes nothing.
3. What it does, and all it does: a message on ``R/stop`` (any payload) or a lock ON on
   ``R/lock``, not a replay (under MQTT 3.1.1 a retained flag means "replayed"; the session
   carries such a stop out once, lastword.py rule 6) nor an empty retained message (the
   deletion of a retained one: service.py rule 1), is one ``os.write`` of that rotator's
   stop frame on its copy of the port, at once, if it holds one. A tty takes one write whole
   against the serial-lines thread's (one write a frame too, engine/port.py), so the frame
   goes between two of the session's frames, never inside one. A write that fails (a full
   buffer, an unplugged adapter) is let go: the session's own stop follows. It decides
   nothing else and changes no state: the session still gets the stop from the lane and the
   main connection, holds, markers and the lock as before, and writes its own stop frame (the
   controller gets two: ModelSpec.stop_anytime says the model takes that). At most one frame
   a rotator in GAP_S: a flood on the stop topic must not fill the port's output buffer (the
   session's own frames would wait behind it, and a full buffer is a lost link, engine/port.py
   rule 6); a second stop that soon adds nothing the first did not do, and the session's
   still comes.
4. Only models whose stop frame may go at any moment (``ModelSpec.stop_anytime``) get a copy
   of their port; elsewhere (a SatEL that slews, a SPID that owes replies) the session alone
   writes, as before.
5. Ports (engine/port.py rule 7): the descriptor of each port opened goes to the express over
   the control socket (SCM_RIGHTS), numbered; before a port is closed the express is told to
   close its copy and says it did, and the closing thread waits for that (DROP_WAIT_S), since a
   copy keeps the tty open and its TIOCEXCL would refuse the reopen (until START_WAIT_S after
   its start while the express has not said a word yet: still starting, not hung). The port
   going is named by its descriptor: a close that runs late, after the rotator's next port was
   handed over (an unplug and replug), leaves that one held (the express closed the old copy
   then). An express that does not answer in time is killed (rule 6) and the port closed all
   the same.
6. Never silent: an express not up within START_WAIT_S, one that ends or is killed, one whose
   connection the broker refuses (said until a connection is accepted) or whose subscription it
   denies is said on ``B/bridge/info`` (``on_problem``); stops then take the stop lane in the
   bridge's process, as without it. An express that ended is not restarted.
7. Shutdown: ``stop`` closes the control socket; the express closes its copies of the ports
   (a bridge restarted at once finds them free), disconnects and exits on its end of file,
   and is killed after STOP_WAIT_S. It exits too when the bridge's process dies (the
   socket's other end closes with it), and only then: it ignores SIGINT and SIGTERM (a service
   manager or a terminal signals the whole group; the bridge stops its rotators first).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

from paho.mqtt.reasoncodes import ReasonCode

from bridge.mqtt.connection import Connection, Ending
from bridge.mqtt.heartbeat import Stamp
from bridge.mqtt.payloads import PayloadError, parse_switch
from bridge.settings import MqttSettings

log = logging.getLogger(__name__)

START_WAIT_S = 10.0  # rule 6: said when the express is not up by then
DROP_WAIT_S = 1.0  # rule 5
STOP_WAIT_S = 2.0  # rule 7
GAP_S = 0.1  # rule 3: one stop frame a rotator in this long, at most
_PACKET = 65536


def express_client_id(settings: MqttSettings) -> str:
    """Rule 2: the lane's rule (lane.py rule 2) with its own mark."""
    main = settings.effective_client_id()
    if settings.client_id is None and main.startswith("rotor-"):
        return "rfast-" + main[len("rotor-") :]
    mine = main + "-fast"
    if len(mine) <= 23:
        return mine
    digest = hashlib.sha256(main.encode()).hexdigest()[:6]
    return f"{main[:11]}-{digest}-fast"


def _send(sock: socket.socket, word: dict[str, Any], fds: list[int] | None = None) -> None:
    data = json.dumps(word).encode()
    if fds:
        socket.send_fds(sock, [data], fds)
    else:
        sock.send(data)


# -- the bridge's side ---------------------------------------------------------------------------
class Express:
    """The child process, seen from the bridge: its ports (rule 5), its start, its problems."""

    def __init__(
        self,
        settings: MqttSettings,
        *,
        topics: dict[str, tuple[str, str]],
        frames: dict[str, bytes],
        on_problem: Callable[[str, bool], None],
        command: list[str] | None = None,
    ) -> None:
        """``topics``: each stop and lock topic -> (rotator id, "stop" or "lock"); ``frames``:
        each rotator of a model with ``stop_anytime`` -> its stop frame (rule 4)."""
        self._settings = settings
        self.client_id = express_client_id(settings)
        self._topics = {t: rk for t, rk in topics.items() if rk[0] in frames}
        self._frames = frames
        self._on_problem = on_problem
        self._command = command or [sys.executable, "-m", "bridge.mqtt.express"]
        self._lock = threading.Lock()  # the ports, the socket, the child
        self._ports: dict[str, tuple[int, int]] = {}  # rotator id -> (number, fd), while open
        self._number = 0
        self._dropped: dict[int, threading.Event] = {}
        self._sock: socket.socket | None = None
        self._child: subprocess.Popen[bytes] | None = None
        self._started = False
        self._stopping = False
        self._said: set[str] = set()
        self.up = threading.Event()  # its connection subscribed (the tests wait for it)
        self.held: set[str] = set()  # the rotators whose port it holds (said by the child)
        self.held_changed = threading.Event()  # set on every change of ``held`` (the tests)
        # (rotator, the child's clock) of the latest frames written (the tests, the log)
        self.wrote: deque[tuple[str, float]] = deque(maxlen=64)
        self.ended = threading.Event()  # the child is gone (rule 6)
        self._heard = threading.Event()  # a word from the child: it reads its socket (rule 5)
        self._started_at = 0.0  # when the child was started (its START_WAIT_S, rule 5)

    @property
    def wanted(self) -> bool:
        """Whether any rotator's model lets the express write its stop (rule 4)."""
        return bool(self._frames)

    def watch(self, rotator_id: str) -> _PortWatch | None:
        """What the rotator's worker tells of its ports (engine/port.py rule 7), where rule 4
        lets the express write."""
        return _PortWatch(self, rotator_id) if rotator_id in self._frames else None

    def start(self, mqtt311: bool) -> None:
        """Rule 1: once, never after ``stop``; the child is started off the caller's thread."""
        with self._lock:
            if self._started or self._stopping or not self._frames:
                return
            self._started = True
        threading.Thread(
            target=self._run, args=(mqtt311,), name="stop express", daemon=True
        ).start()

    def stop(self) -> None:
        """Rule 7."""
        with self._lock:
            self._stopping = True
            sock, child = self._sock, self._child
        if sock is not None:
            try:
                sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        if child is not None:
            try:
                child.wait(STOP_WAIT_S)
            except subprocess.TimeoutExpired:
                child.kill()
                child.wait()

    # -- the ports (engine/port.py rule 7, on the ports' open and close threads) ---------------
    def opened(self, rotator_id: str, fd: int) -> None:
        with self._lock:
            self._number += 1
            self._ports[rotator_id] = (self._number, fd)
            if self._sock is not None:
                self._hand(rotator_id, self._number, fd)

    def closing(self, rotator_id: str, fd: int) -> None:
        with self._lock:
            number, held = self._ports.get(rotator_id, (0, -1))
            if held != fd:
                return  # a newer port's (its close ran late): the express dropped this copy
            del self._ports[rotator_id]
            if self._sock is None or self.ended.is_set():
                return
            dropped = self._dropped[number] = threading.Event()
            try:
                _send(self._sock, {"op": "drop", "rotator": rotator_id, "n": number})
            except OSError:
                return  # gone: its copies are closed with it
        # not reading its socket yet is a start (importing Python on a slow machine), no hang
        wait_s = DROP_WAIT_S
        if not self._heard.is_set():
            wait_s = max(wait_s, self._started_at + START_WAIT_S - time.monotonic())
        if not dropped.wait(wait_s):
            self._kill(f"did not give {rotator_id}'s port back within {wait_s:.1f} s")
        with self._lock:
            self._dropped.pop(number, None)

    def _hand(self, rotator_id: str, number: int, fd: int) -> None:
        """Under the lock: a copy of the port to the child (rule 5)."""
        assert self._sock is not None
        try:
            _send(self._sock, {"op": "port", "rotator": rotator_id, "n": number}, [fd])
        except OSError as exc:
            log.warning("stop express: could not hand over %s's port: %s", rotator_id, exc)

    # -- the child (rule 1, on the express's thread) -------------------------------------------
    def _run(self, mqtt311: bool) -> None:
        t0 = self._started_at = time.monotonic()
        mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        env = dict(os.environ)
        root = str(Path(__file__).resolve().parents[2])  # the bridge's own code, whatever runs it
        env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
        try:
            child = subprocess.Popen(
                [*self._command, str(theirs.fileno())],
                pass_fds=[theirs.fileno()],
                stdin=subprocess.DEVNULL,
                env=env,
                close_fds=True,
            )
        except OSError as exc:
            theirs.close()
            mine.close()
            self._ended(f"the stop express could not start: {exc}")
            return
        theirs.close()
        s = self._settings
        secret = s.password.get_secret_value() if s.password is not None else None
        config = {
            "op": "config",
            "mqtt": {**s.model_dump(mode="json"), "password": secret, "password_file": None},
            "client_id": self.client_id,
            "mqtt311": mqtt311,
            "topics": self._topics,
            "frames": {rid: frame.hex() for rid, frame in self._frames.items()},
            "log_level": logging.getLogger("bridge").getEffectiveLevel(),
        }
        with self._lock:
            self._child = child
            if self._stopping:
                mine.close()
                child.kill()
                child.wait()
                return
            try:
                _send(mine, config)
            except OSError:
                pass  # it died at once: read below as an end of file
            self._sock = mine
            for rid, (number, fd) in self._ports.items():
                self._hand(rid, number, fd)
        mine.settimeout(START_WAIT_S)
        late = f"the stop express did not come up within {START_WAIT_S:g} s"
        passing: set[str] = set()  # problems said until it is up (rule 6)
        while True:
            try:
                data = mine.recv(_PACKET)
            except TimeoutError:
                self._problem(late, True)
                mine.settimeout(None)
                continue
            except OSError:
                data = b""
            if not data:
                break
            self._heard.set()
            word = json.loads(data)
            op = word.get("op")
            if op == "up":
                mine.settimeout(None)
                for text in (late, *passing):
                    self._problem(text, False)
                passing.clear()
                if not self.up.is_set():
                    log.info(
                        "stop express up as %s (pid %d, %.2f s)",
                        self.client_id,
                        child.pid,
                        time.monotonic() - t0,
                    )
                self.up.set()
            elif op == "held":
                self._held(word["rotator"], True)
            elif op == "dropped":
                self._held(word["rotator"], False)
                with self._lock:
                    event = self._dropped.get(word["n"])
                if event is not None:
                    event.set()
            elif op == "wrote":
                self.wrote.append((word["rotator"], word["t"]))
                log.debug("stop express: %s's stop frame written", word["rotator"])
            elif op == "problem":
                text = f"stop express: {word['text']}"
                self._problem(text, True)
                if word.get("until_up"):  # a connection refused: said until one is accepted
                    passing.add(text)
        try:
            code = child.wait(STOP_WAIT_S)
        except subprocess.TimeoutExpired:
            child.kill()
            code = child.wait()
        with self._lock:
            stopping = self._stopping
            self._sock = None
            waiting = list(self._dropped.values())
        for event in waiting:  # its copies of the ports went with it
            event.set()
        mine.close()
        if not stopping:
            self._ended(f"the stop express ended (exit code {code})")
        else:
            self.ended.set()

    def _held(self, rotator_id: str, held: bool) -> None:
        if held:
            self.held.add(rotator_id)
        else:
            self.held.discard(rotator_id)
        self.held_changed.set()

    def _kill(self, why: str) -> None:
        with self._lock:
            child = self._child
        log.error("stop express %s: killed", why)
        if child is not None:
            child.kill()  # its copies of the ports close with it; _run says it ended

    def _ended(self, why: str) -> None:
        """Rule 6."""
        self.up.clear()
        self.held.clear()
        self.ended.set()
        for event in list(self._dropped.values()):
            event.set()
        self._problem(f"{why}: stops take the stop lane in the bridge's process", True)

    def _problem(self, text: str, on: bool) -> None:
        if on == (text in self._said):
            return
        if on:
            self._said.add(text)
            log.error("%s", text)
        else:
            self._said.discard(text)
        try:
            self._on_problem(text, on)
        except Exception:
            log.exception("error reporting a problem of the stop express")


class _PortWatch:
    """One rotator's ports, told to the express (engine/port.py PortWatch)."""

    def __init__(self, express: Express, rotator_id: str) -> None:
        self._express = express
        self._id = rotator_id

    def opened(self, fd: int) -> None:
        self._express.opened(self._id, fd)

    def closing(self, fd: int) -> None:
        self._express.closing(self._id, fd)


# -- the child's side ----------------------------------------------------------------------------
class _Link(Connection):
    """The express's connection (rule 2): the lane's hooks, its words to the bridge."""

    def __init__(self, settings: MqttSettings, client_id: str, say: Callable[..., None], **kw: Any):
        super().__init__(settings, client_id, **kw)
        self._auto = False  # the main connection settled the protocol (rule 2)
        self._say = say

    def _refused(self, reason: str) -> None:
        self._say(
            op="problem", text=f"the MQTT broker refused its connection: {reason}", until_up=True
        )

    def _failed(self) -> None:
        pass  # the main connection says why the broker cannot be reached

    def _accepted(self) -> None:
        pass

    def _denied(self, topic: str, reason: str) -> None:
        self._say(
            op="problem", text=f"the MQTT broker does not let it subscribe to {topic}: {reason}"
        )

    def _closed_early(self, reason: str) -> None:
        pass

    def _closed(self, was_up: bool, reason_code: ReasonCode) -> bool:
        if not was_up:
            text = f"the MQTT broker closed its connection: {reason_code}"
            self._say(op="problem", text=text, until_up=True)
        return was_up

    def _ended(self, reason_code: ReasonCode, ending: Ending, fight: bool) -> None:
        log.debug("stop express disconnected (%s)", reason_code)


class _Child:
    """The express itself (rules 3 and 5): the ports it holds, the frames it writes."""

    def __init__(self, sock: socket.socket, config: dict[str, Any]) -> None:
        self._sock = sock
        self._send_lock = threading.Lock()
        self._lock = threading.Lock()  # the ports: never closed while written to
        self._ports: dict[str, tuple[int, int]] = {}  # rotator id -> (number, fd)
        self._topics: dict[str, tuple[str, str]] = {
            t: (r, k) for t, (r, k) in config["topics"].items()
        }
        self._frames = {rid: bytes.fromhex(f) for rid, f in config["frames"].items()}
        self._v5 = not config["mqtt311"]
        self._next: dict[str, float] = {}  # rotator id -> when it may get a frame again (rule 3)
        self.clock: Callable[[], float] = time.monotonic
        settings = MqttSettings.model_validate(config["mqtt"])
        self.link = _Link(
            settings,
            config["client_id"],
            self.say,
            subscriptions=list(self._topics),
            on_message=self.on_message,
            on_subscribed=lambda: self.say(op="up"),
            no_replay=list(self._topics),
        )
        if config["mqtt311"]:
            self.link.use_mqtt311()

    def say(self, **word: Any) -> None:
        with self._send_lock:
            try:
                _send(self._sock, word)
            except OSError:
                pass  # the bridge is gone: the main loop ends on it

    def on_message(
        self, topic: str, payload: bytes, retain: bool, operator: str | None, stamp: Stamp | None
    ) -> None:
        """Rule 3, on paho's thread."""
        where = self._topics.get(topic)
        if where is None or (retain and (not self._v5 or not payload)):
            return  # a replay (3.1.1), or a retained message being deleted (service.py rule 1)
        rid, kind = where
        if kind == "lock" and not _switch_on(payload):
            return
        with self._lock:
            held, now = self._ports.get(rid), self.clock()
            if held is None or now < self._next.get(rid, now):
                return
            try:
                os.write(held[1], self._frames[rid])
            except OSError:
                return  # rule 3: the session's own stop follows
            self._next[rid] = now + GAP_S
        self.say(op="wrote", rotator=rid, t=now)

    def serve(self) -> None:
        """The bridge's words until its end of file (rule 7)."""
        while True:
            try:
                data, fds, _flags, _addr = socket.recv_fds(self._sock, _PACKET, 4)
            except OSError:
                break
            if not data:
                break
            word = json.loads(data)
            rid, number = word.get("rotator"), word.get("n")
            if word.get("op") == "port" and fds:
                with self._lock:
                    old = self._ports.get(rid)
                    self._ports[rid] = (number, fds[0])
                if old is not None:
                    os.close(old[1])
                self.say(op="held", rotator=rid, n=number)
            elif word.get("op") == "drop":
                with self._lock:
                    held = self._ports.get(rid)
                    if held is not None and held[0] == number:
                        del self._ports[rid]
                        os.close(held[1])
                self.say(op="dropped", rotator=rid, n=number)
            for extra in fds[1:] if word.get("op") == "port" else fds:
                os.close(extra)
        with self._lock:  # the bridge is gone: its ports are free at once (rule 7)
            for _number, fd in self._ports.values():
                os.close(fd)
            self._ports.clear()


def _switch_on(payload: bytes) -> bool:
    try:
        return parse_switch(payload)
    except PayloadError:
        return False


def main(argv: list[str]) -> int:
    sock = socket.socket(fileno=int(argv[1]))
    data = sock.recv(_PACKET)
    if not data:
        return 0
    config = json.loads(data)
    for sig in (signal.SIGINT, signal.SIGTERM):  # rule 7: it ends with the bridge, not before
        signal.signal(sig, signal.SIG_IGN)
    logging.basicConfig(
        level=config.get("log_level", logging.INFO),
        format="stop express: %(levelname)s %(message)s",
    )
    child = _Child(sock, config)
    child.link._connect()
    try:
        child.serve()
    finally:
        child.link._disconnect()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
