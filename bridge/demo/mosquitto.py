"""The demo's private mosquitto: a broker process on a loopback port, started only when nothing
answers at the demo's MQTT address, stopped with the demo. (The tests' broker,
tests/support/mosquitto.py, is this one with what only tests need: a configuration of their own,
a crash, a freeze, a restart.)

(We tried amqtt as an embedded broker: 0.12.1 moved the bridge's subscriptions to a later
anonymous client's session, after which the bridge silently received no commands. Debian's
mosquitto is what the tests and production use anyway.)

Started means this broker listens: its log (``-v``) says it runs, which it says only once every
listener is bound. Another program on the port answers too, before mosquitto has even tried
to bind it; mosquitto then exits ("Address already in use") and every client would reach the
other program's broker instead (under parallel tests: another test's, which this one's
freezing and restarting then never touch).

The demo's broker dies with the demo (``dies_with_parent``), however the demo ends: a demo killed
with SIGKILL, or by the out-of-memory killer, runs no clean-up, and its broker ran on for good,
answering on the port, where the next demo took it for the user's own broker. The kernel sends
it SIGTERM when the thread that started it ends (``PR_SET_PDEATHSIG``, set between fork and
exec; the demo starts it from its main thread, before it starts any other thread). The kernel
forgets that signal when a process changes its user, as mosquitto started by root does (to the
user ``mosquitto``, unless told ``user root``): run as root, its configuration says ``user root``;
run by anyone else it never changes user. It listens on the loopback address only.

A broker answers (``answers``; ``connack`` with its code) when a CONNECT gets a CONNACK within
the time the bridge gives one (CONNACK_TIMEOUT_S): a program that only takes connections
(``listens``) may speak no MQTT at all, and a demo bridged to it would run dead. One whose
CONNACK refuses the login (LOGIN_REFUSED) cannot be the demo's: it has no login to give; nor
can one that bans it (BANNED).
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import math
import os
import re
import shutil
import signal
import socket
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import Self

from bridge.core.polling import POLLIN, POLLOUT, new_poller
from bridge.interfaces.mqtt.paho_client import CONNACK_TIMEOUT_S


class BrokerError(RuntimeError):
    pass


def find_mosquitto() -> str | None:
    return shutil.which("mosquitto") or next(
        (p for p in ("/usr/sbin/mosquitto", "/usr/local/sbin/mosquitto") if Path(p).exists()), None
    )


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def listens(host: str, port: int, timeout_s: float = 0.5) -> bool:
    """Whether something takes connections at host:port (any program: see ``answers``)."""
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            return True
    except OSError:
        return False


# A CONNECT with a clean session, keep-alive 10 s and an empty client id (the broker makes one
# up): MQTT 5 first, as the bridge and the demo's console connect, then MQTT 3.1.1 (every broker
# speaks it; the bridge's ``protocol = "auto"`` steps down to it, connection.py rule 1)
_CONNECT_5 = bytes([0x10, 13, 0, 4]) + b"MQTT" + bytes([5, 0x02, 0, 10, 0, 0, 0])  # no properties
_CONNECT_311 = bytes([0x10, 12, 0, 4]) + b"MQTT" + bytes([4, 0x02, 0, 10, 0, 0])
_CONNACK = 0x20
_DISCONNECT = bytes([0xE0, 0])
# a CONNACK's code that says "not this protocol version": MQTT 5's 0x84; 1, a 3.1.1 broker's
# answer to an MQTT 5 CONNECT (its "unacceptable protocol version")
_OTHER_VERSION = frozenset({0x84, 0x01})
# the look waits in slices this long, each ended by ``ended`` (the demo's ^C, SIGTERM): a wait
# of the bridge's whole CONNACK_TIMEOUT_S is no time for a user's ^C to be held (review 127)
LOOK_SLICE_S = 0.05


def _never() -> bool:
    return False


def connack(
    host: str,
    port: int,
    timeout_s: float = CONNACK_TIMEOUT_S,
    ended: Callable[[], bool] = _never,
) -> int | None:
    """The code of the CONNACK a broker at host:port answers the demo's CONNECT with (0:
    accepted; a refusal's code, in MQTT 5's words where it spoke MQTT 5), or None: nothing took
    the connection, or no CONNACK came within ``timeout_s`` (as long as the bridge waits for
    one: paho_client.py rule 5; review 122). MQTT 5 first; MQTT 3.1.1 when that connection was
    closed before a CONNACK or refused for its protocol version (an MQTT 3.1.1 broker), as the
    bridge steps down (connection.py rule 1); a broker that speaks MQTT 5 alone closes the
    3.1.1 CONNECT, so it is never asked that first. None too as soon as ``ended()`` says the
    demo ends: it is asked between slices of the wait (LOOK_SLICE_S; the name's look-up alone
    is not sliced)."""
    answer = connack_of(host, port, timeout_s, ended)
    return None if answer is None else answer[0]


def connack_of(
    host: str,
    port: int,
    timeout_s: float = CONNACK_TIMEOUT_S,
    ended: Callable[[], bool] = _never,
) -> tuple[int, bool] | None:
    """``connack``'s answer with the protocol that got it: (the code, True for MQTT 5 and False
    for MQTT 3.1.1). The demo's console connects in the protocol the broker answered (review 127:
    on a 3.1.1-only broker it spoke MQTT 5 alone and was refused for the whole run). MQTT 3.1.1
    only where the broker refused MQTT 5 for its version, or closed it twice around a 3.1.1
    CONNECT it answered: one close is also a broker restarting, as the bridge's own step-down
    judges (connection.py rule 1; review 134: one close took an MQTT 5 broker for 3.1.1)."""
    deadline = time.monotonic() + timeout_s
    code = _connack(host, port, _CONNECT_5, deadline, ended)
    v5 = True
    if code is None or code in _OTHER_VERSION:
        code311 = _connack(host, port, _CONNECT_311, deadline, ended)
        if code is None and code311 is not None and code311 >= 0:  # (closed: asked again)
            again = _connack(host, port, _CONNECT_5, deadline, ended)
            if again is not None and again >= 0 and again not in _OTHER_VERSION:
                return again, True
        if code311 is not None or code is None:
            code, v5 = code311, False
    return None if code is None or code < 0 else (code, v5)


def _connack(
    host: str, port: int, connect: bytes, deadline: float, ended: Callable[[], bool]
) -> int | None:
    """One CONNECT: the CONNACK's code; None: no connection, closed before the CONNACK, or
    something else than MQTT; -1: no CONNACK by ``deadline``, or ``ended()`` (no second try: it
    would wait again)."""
    try:
        with _connect(host, port, deadline, ended) as s:
            s.sendall(connect)  # (a dozen bytes: the new socket's buffer takes them at once)
            if _read(s, 1, deadline, ended) != bytes([_CONNACK]):
                return None
            length, shift = 0, 0  # the remaining length: 2 in 3.1.1, more with MQTT 5's properties
            while True:
                byte = _read(s, 1, deadline, ended)[0]
                length |= (byte & 0x7F) << shift
                shift += 7
                if not byte & 0x80 or shift > 21:
                    break
            if not 2 <= length <= 0xFFFF:  # (a CONNACK's properties are short)
                return None
            code = _read(s, 2, deadline, ended)[1]  # (flags first)
            with contextlib.suppress(OSError):
                s.sendall(_DISCONNECT)
            return code
    except TimeoutError:
        return -1
    except (OSError, EOFError):
        return None


def _slice_ms(deadline: float, ended: Callable[[], bool]) -> int:
    """The next slice of a wait, in ms; TimeoutError once ``deadline`` passed or ``ended()``."""
    left = deadline - time.monotonic()
    if left <= 0 or ended():
        raise TimeoutError
    return math.ceil(min(left, LOOK_SLICE_S) * 1000)


def _connect(host: str, port: int, deadline: float, ended: Callable[[], bool]) -> socket.socket:
    """``socket.create_connection``, its wait in slices (``_slice_ms``): a non-blocking
    socket, connected to host:port's first address that takes it."""
    failed: OSError = OSError(f"no address for {host}")
    for family, kind, proto, _, address in socket.getaddrinfo(host, port, 0, socket.SOCK_STREAM):
        s = socket.socket(family, kind, proto)
        try:
            s.setblocking(False)
            err = s.connect_ex(address)
            if err not in (0, errno.EINPROGRESS):
                raise OSError(err, os.strerror(err))
            poller = new_poller()
            poller.register(s, POLLOUT)
            while not poller.poll(_slice_ms(deadline, ended)):
                pass
            err = s.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if err:
                raise OSError(err, os.strerror(err))
            return s
        except TimeoutError:
            s.close()
            raise
        except OSError as exc:
            s.close()
            failed = exc
    raise failed


def _read(s: socket.socket, n: int, deadline: float, ended: Callable[[], bool]) -> bytes:
    poller = new_poller()
    poller.register(s, POLLIN)
    got = b""
    while len(got) < n:
        if not poller.poll(_slice_ms(deadline, ended)):
            continue
        chunk = s.recv(n - len(got))
        if not chunk:  # closed without a CONNACK
            raise EOFError
        got += chunk
    return got


# a CONNACK that refuses the login (MQTT 5's codes, and 3.1.1's): the demo has none to give
LOGIN_REFUSED = {
    0x86: "bad user name or password",
    0x87: "not authorized",
    0x8C: "bad authentication method",
    4: "bad user name or password",
    5: "not authorized",
}
# a CONNACK that shuts the demo out however it connects: MQTT 5's 0x8A "banned" (EMQX's banned
# list, its flapping detection, keyed by the client's address); a broker that says so cannot be
# the demo's any more than one that refuses its login (review 127). (A 3.1.1 broker says 5.)
BANNED = {0x8A: "banned"}


def answers(
    host: str,
    port: int,
    timeout_s: float = CONNACK_TIMEOUT_S,
    ended: Callable[[], bool] = _never,
) -> bool:
    """Whether an MQTT broker answers at host:port: a CONNECT gets a CONNACK within
    ``timeout_s``, as long as the bridge waits for one (paho_client.py rule 5: a broker slower
    than the demo's look but quicker than that serves the bridge, review 122). A program that
    takes connections and says nothing, or something else than MQTT (a hung broker, an SSH
    tunnel whose far end is gone, a web server), is no broker: the demo would run dead on it.
    A broker that refuses the demo's login answers too (``connack``, LOGIN_REFUSED). False
    as soon as ``ended()``."""
    return connack(host, port, timeout_s, ended) is not None


_RUNNING = re.compile(rb"mosquitto version \S+ running")  # said once every listener is bound

_PR_SET_PDEATHSIG = 1  # linux/prctl.h


def _dies_with_this_thread() -> Callable[[], None] | None:
    """A child's step before exec: SIGTERM when the thread that forks it ends (None where the
    system has no ``prctl``). Everything it needs is looked up here, before the fork: the child
    only calls it."""
    prctl = getattr(ctypes.CDLL(None, use_errno=True), "prctl", None)
    if prctl is None:
        return None
    parent = os.getpid()

    def before_exec() -> None:
        prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
        if os.getppid() != parent:  # the parent died before the signal was asked for
            os._exit(1)

    return before_exec


class Mosquitto:
    """``start()``/``stop()``; a free port unless one is given."""

    def __init__(
        self,
        workdir: Path,
        *,
        port: int | None = None,
        host: str = "127.0.0.1",
        dies_with_parent: bool = False,
    ) -> None:
        exe = find_mosquitto()
        if exe is None:
            raise BrokerError(
                "mosquitto is not installed (Debian/Ubuntu: sudo apt-get install mosquitto)"
            )
        self.exe = exe
        self.host = host
        self.port = port or free_port()
        self.workdir = workdir
        self.conf = workdir / "mosquitto.conf"
        self.log = workdir / "mosquitto.log"
        self.dies_with_parent = dies_with_parent
        self.proc: subprocess.Popen[bytes] | None = None

    def config(self) -> str:
        """mosquitto.conf: one listener, nothing kept, anyone may connect (the demo's own); run
        as root and dying with its parent, it stays root (the kernel's death signal would be
        forgotten as it changed user)."""
        root = "user root\n" if self.dies_with_parent and os.geteuid() == 0 else ""
        return f"listener {self.port} {self.host}\npersistence false\nallow_anonymous true\n{root}"

    def start(self, timeout_s: float = 10.0) -> Self:
        self.workdir.mkdir(parents=True, exist_ok=True)
        self.conf.write_text(self.config())
        with open(self.log, "ab") as log:
            logged = log.tell()  # (the log of an earlier start on the same path stays before it)
            self.proc = subprocess.Popen(  # noqa: PLW1509 (no other thread runs yet: see above)
                [self.exe, "-c", str(self.conf), "-v"],
                stdout=log,
                stderr=subprocess.STDOUT,
                preexec_fn=_dies_with_this_thread() if self.dies_with_parent else None,
            )
        deadline = time.monotonic() + timeout_s
        while not (self._running(logged) and listens(self.host, self.port, 0.2)):
            if self.proc.poll() is not None:
                raise BrokerError(f"mosquitto exited: {self.log.read_text()[-2000:]}")
            if time.monotonic() > deadline:
                self.stop()
                raise BrokerError(f"mosquitto did not listen on {self.host}:{self.port}")
            time.sleep(0.02)
        return self

    def _running(self, logged: int) -> bool:
        """Whether the log since ``logged`` says mosquitto runs: all its listeners are bound."""
        with open(self.log, "rb") as log:
            log.seek(logged)
            return _RUNNING.search(log.read()) is not None

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None
