"""A CI failure of review 88's proxy-restart test (tests/faults/), made deterministic: real
mosquitto, the bridge in this process, the stop express in its own and a Rotor-EZ on a real pty.

After a broker restart the stop express, on its 2 s back-off, is often the first of the bridge's
connections back. It writes no frame until a sync word it published on that connection came back
(express.py rule 8: only then can its frames be ordered against the bridge's holds). A STOP it
read in between, while neither of the bridge's own connections was subscribed (they start clean:
no copy ever comes to them), was dropped without a word: no frame, and no ``heard`` for the bridge
to carry out (rule 11), so the rotor turned on to its target. The CI run published its STOP just
after the express's SUBSCRIBE showed in the broker's log, a round trip before its word came back,
and the lanes subscribed a few milliseconds after the STOP.

The window is held open here: an ACL drops the express's sync words (its word never comes back,
so it never writes), and the bridge's two connections stay away (their back-off made long), as in
tests/integration/test_stop_express.py's ``express_alone``.

Such a stop is said ``early`` and judged by the halts the bridge's connections read alone, not by
the express's vouches (express.py rule 11): a vouch it answered at once while subscribed and not
yet writing says nothing of a stop it reads after it. The second test reads the STOP late on
purpose, behind a proxy that holds what the broker sends the express, until the stop lane, which
subscribed after the STOP, has been vouched for so.
"""

from __future__ import annotations

import contextlib
import socket
import threading
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.express import express_client_id
from bridge.interfaces.mqtt.lane import lane_client_id
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

OPEN = "topic readwrite rotor/#\ntopic readwrite homeassistant/#\n"
WORDS = "rotor/bridge/fence/express"  # the express's sync topic (express.py rule 8)


@pytest.fixture
def broker_conf(tmp_path: Path) -> str:
    (tmp_path / "words.acl").write_text(OPEN)
    return f"allow_anonymous true\nacl_file {tmp_path / 'words.acl'}\nuser root"


def test_a_stop_the_express_reads_before_its_word_is_back_stops_the_rotor(
    rig: Rig, broker: Mosquitto, tmp_path: Path
) -> None:
    rig.express = True
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
    app = rig.start()
    rig.ready("tower")
    wait_until(app.express.up.is_set, 10, "the express up")
    wait_until(lambda: "tower" in app.express.held, 10, "the express holds the port")
    rig.probe.publish("rotor/target", "300")  # a long turn (145 s)
    emu.wait_for(lambda s: s.is_moving, slow(10))
    app.client._client.reconnect_delay_set(60, 60)  # the bridge's connections back late
    app.lane._client.reconnect_delay_set(60, 60)
    (tmp_path / "words.acl").write_text(f"{OPEN}topic deny {WORDS}\n")  # its words dropped
    start = broker.log.stat().st_size
    broker.restart()
    denied = f"Denied PUBLISH from {app.express.client_id}"  # its first word: it is subscribed
    wait_until(
        lambda: denied in broker.log.read_bytes()[start:].decode(errors="replace"),
        15,
        "the express back and subscribed, its word dropped",
    )
    assert not app.client.connected.is_set() and not app.lane.connected.is_set()
    assert not app.express.up.is_set()  # (it may not write: rule 8)
    operator = Probe(broker.port, "")
    try:
        assert operator.publish("rotor/stop", "STOP")  # the operator's STOP
    finally:
        operator.close()
    emu.wait_for(lambda s: not s.is_moving, slow(10))


def _client_id(packet: bytes) -> str | None:
    """The client id of an MQTT CONNECT (3.1.1 or 5) read whole, else None."""
    try:
        if packet[0] != 0x10:
            return None
        i = 1
        while packet[i] & 0x80:  # the remaining length
            i += 1
        i += 1
        i += 2 + int.from_bytes(packet[i : i + 2], "big")  # the protocol's name
        level, i = packet[i], i + 4  # level, flags, keep-alive
        if level == 5:  # its properties
            length, shift = 0, 0
            while True:
                byte, i = packet[i], i + 1
                length, shift = length | (byte & 0x7F) << shift, shift + 7
                if not byte & 0x80:
                    break
            i += length
        n = int.from_bytes(packet[i : i + 2], "big")
        return packet[i + 2 : i + 2 + n].decode()
    except (IndexError, UnicodeDecodeError):
        return None


class _Gate:
    """A TCP proxy in front of the broker that knows each connection by its client id: those
    in ``refused`` are closed at once (the broker away, for them alone), and while ``holding``
    what the broker sends the connection of ``held_id`` waits here, in order."""

    def __init__(self, backend: int) -> None:
        self._backend = backend
        self.held_id = ""
        self.refused: set[str] = set()
        self._cond = threading.Condition()
        self._holding = False
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port = self._listener.getsockname()[1]
        self._socks: list[socket.socket] = []
        threading.Thread(target=self._serve, daemon=True).start()

    def hold(self, on: bool) -> None:
        with self._cond:
            self._holding = on
            self._cond.notify_all()

    def _serve(self) -> None:
        while True:
            try:
                client, _addr = self._listener.accept()
            except OSError:
                return
            threading.Thread(target=self._join, args=(client,), daemon=True).start()

    def _join(self, client: socket.socket) -> None:
        try:
            connect = client.recv(65536)
            who = _client_id(connect)
            if who is None or who in self.refused:
                client.close()
                return
            server = socket.create_connection(("127.0.0.1", self._backend))
            server.sendall(connect)
        except OSError:
            client.close()
            return
        self._socks += [client, server]
        threading.Thread(target=self._pipe, args=(client, server, False), daemon=True).start()
        self._pipe(server, client, who == self.held_id)

    def _pipe(self, a: socket.socket, b: socket.socket, held: bool) -> None:
        with contextlib.suppress(OSError):
            while data := a.recv(65536):
                with self._cond:
                    self._cond.wait_for(lambda: not (held and self._holding))
                b.sendall(data)
        with contextlib.suppress(OSError):
            b.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self.hold(False)
        self._listener.close()
        for s in self._socks:
            s.close()


def test_a_stop_the_express_reads_early_is_carried_out_though_a_lane_was_vouched_for_since(
    tmp_path: Path, broker: Mosquitto
) -> None:
    """The STOP is published while only the express is subscribed (its words dropped: not
    writing), and read by it late, after the stop lane subscribed and the express answered the
    lane's vouch at once. Judged by that vouch, the stop was the lane's, which never had it."""
    gate = _Gate(broker.port)
    probe = Probe(broker.port, "rotor/#")  # a dashboard on the broker's own port
    try:
        with Rig(tmp_path, gate, probe) as rig:
            rig.express = True
            emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            settings = rig.settings.mqtt
            gate.held_id = express_client_id(settings)
            app = rig.start()
            rig.ready("tower")
            wait_until(app.express.up.is_set, 10, "the express up")
            wait_until(lambda: "tower" in app.express.held, 10, "the express holds the port")
            probe.publish("rotor/target", "300")  # a long turn (145 s)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            gate.refused |= {settings.effective_client_id(), lane_client_id(settings)}
            (tmp_path / "words.acl").write_text(f"{OPEN}topic deny {WORDS}\n")
            start = broker.log.stat().st_size
            broker.restart()
            denied = f"Denied PUBLISH from {app.express.client_id}"
            wait_until(
                lambda: denied in broker.log.read_bytes()[start:].decode(errors="replace"),
                15,
                "the express back and subscribed, its word dropped",
            )
            assert not app.client.connected.is_set() and not app.lane.connected.is_set()
            gate.hold(True)  # what the broker sends the express waits at the gate
            assert probe.publish("rotor/stop", "STOP")  # the operator's STOP, for it alone
            gate.refused.discard(lane_client_id(settings))  # the stop lane back after it

            def vouched() -> bool:  # the lane's subscription answered for, at once
                since = app.express.vouched("lane")
                return since is not None and app.lane.heard_since(since)

            wait_until(vouched, 15, "the stop lane back and vouched for")
            gate.hold(False)  # the express reads the STOP now
            emu.wait_for(lambda s: not s.is_moving, slow(10))
    finally:
        probe.close()
        gate.close()
