"""Review 108: ``halts.read_since`` lets a lock ON the lock lane read stand for a stop the stop
express reads, because the lane "has had its command topics without a break since"; but the
lock lane subscribes to ``R/lock`` alone (lastword.py rule 16), so no STOP ever reaches it. With
the main connection and the stop lane away, a STOP only the express read (early: it writes no
frame, express.py rules 8, 11) is judged carried out by a lock ON of hours ago, and the bridge
drops it: the rotor turns on to its target.

Real mosquitto (an ACL dropping the express's sync words: it never writes, every stop it reads
is said early), the bridge in this process, the express in its own, a Rotor-EZ on a real pty; a
proxy in front of the broker cuts the main connection and the stop lane (and keeps them out)
while the lock lane and the express stay connected.
"""

from __future__ import annotations

import contextlib
import socket
import threading
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.integration.test_stop_before_the_express_words_are_back import (
    OPEN,
    WORDS,
    _client_id,
)
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until


@pytest.fixture
def broker_conf(tmp_path: Path) -> str:
    (tmp_path / "words.acl").write_text(f"{OPEN}topic deny {WORDS}\n")
    return f"allow_anonymous true\nacl_file {tmp_path / 'words.acl'}\nuser root"


class _Cutter:
    """A TCP proxy in front of the broker that knows each connection by its client id and can
    cut those named (and keep them out from then on)."""

    def __init__(self, backend: int) -> None:
        self._backend = backend
        self._refused: set[str] = set()
        self._lock = threading.Lock()
        self._socks: dict[str, list[socket.socket]] = {}
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port = self._listener.getsockname()[1]
        threading.Thread(target=self._serve, daemon=True).start()

    def cut(self, ids: set[str]) -> None:
        with self._lock:
            self._refused |= ids
            socks = [s for who in ids for s in self._socks.pop(who, [])]
        for s in socks:
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)
            s.close()

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
            who = _client_id(connect) or ""
            with self._lock:
                if who in self._refused:
                    client.close()
                    return
            server = socket.create_connection(("127.0.0.1", self._backend))
            server.sendall(connect)
        except OSError:
            client.close()
            return
        with self._lock:
            self._socks.setdefault(who, []).extend([client, server])
        threading.Thread(target=self._pipe, args=(client, server), daemon=True).start()
        self._pipe(server, client)

    @staticmethod
    def _pipe(a: socket.socket, b: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while data := a.recv(65536):
                b.sendall(data)
        with contextlib.suppress(OSError):
            b.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self._listener.close()
        with self._lock:
            socks = [s for group in self._socks.values() for s in group]
        for s in socks:
            s.close()


def test_a_stop_only_the_express_read_is_not_vetoed_by_a_lock_on_of_the_lock_lane(
    tmp_path: Path, broker: Mosquitto
) -> None:
    cutter = _Cutter(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, cutter, probe) as rig:
            rig.express = True
            emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            settings = rig.settings.mqtt
            app = rig.start()
            rig.ready("tower")
            wait_until(lambda: "tower" in app.express.held, 10, "the express holds the port")
            assert probe.publish("rotor/lock", "ON")  # work on the tower, then done
            probe.wait_value("rotor/lock/state", "ON")
            assert probe.publish("rotor/lock", "OFF")
            wait_until(lambda: not rig.status("tower").locked, 10, "unlocked")  # (both read)
            assert probe.publish("rotor/target", "300")  # a long turn (145 s)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            cutter.cut({settings.effective_client_id(), lane_client_id(settings)})
            wait_until(
                lambda: app.client.subscribed_since is None and app.lane.subscribed_since is None,
                15,
                "the main connection and the stop lane gone",
            )
            assert app.lock_lane.subscribed_since is not None  # (the lock lane stays)
            assert probe.publish("rotor/stop", "STOP")  # read by the express alone
            emu.wait_for(lambda s: not s.is_moving, slow(10))
    finally:
        probe.close()
        cutter.close()
