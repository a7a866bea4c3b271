"""Review 114: d8136809 lets a move the main connection read order the stop express's ``early``
STOP before it, when that connection "has had its topics without a break since" (halts.py
``read_since``; connection.py ``heard_since``: its SUBACK's time, while the connection is up).
A dead path under the bridge's connections (client.py rule 21, 68346e15) is a break nobody has
seen yet: the connection is still up, its subscription still dated before the move, and what
the broker sends it is lost. A STOP published then reaches the express alone, which, a
connection of its own new (its sync word not back: no frame), says it ``early``; the bridge
drops it for the move the main connection read before the path died, and the rotor turns on to
that move's target. Before d8136809 such a STOP was carried out (no connection had read a halt).

Real mosquitto, the bridge in this process, the express in its own, a Rotor-EZ on a real pty. A
proxy in front of the broker (as tests/integration/test_stop_before_the_express_words_are_back.py's
gate) swallows, from a moment on, what the broker sends the bridge's main connection and stop
lane as they are then (a dead path: nothing comes, nothing is closed); connections made after
that pass. The express's sync words are dropped by an ACL (every word it reads is early), and it
is made to connect again (``redial``, express.py rule 12).
"""

from __future__ import annotations

import contextlib
import socket
import threading
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.express import express_client_id
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
    (tmp_path / "words.acl").write_text(OPEN)
    return f"allow_anonymous true\nacl_file {tmp_path / 'words.acl'}\nuser root"


class _DeadPaths:
    """A TCP proxy in front of the broker; ``kill(ids)``: what the broker sends the connections
    of those client ids open now is swallowed from then on (their path dead, unseen)."""

    def __init__(self, backend: int) -> None:
        self._backend = backend
        self._lock = threading.Lock()
        self._open: list[tuple[str, list[bool]]] = []  # client id, [dead]
        self._socks: list[socket.socket] = []
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port = self._listener.getsockname()[1]
        threading.Thread(target=self._serve, daemon=True).start()

    def kill(self, ids: set[str]) -> None:
        with self._lock:
            for who, dead in self._open:
                if who in ids:
                    dead[0] = True

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
            server = socket.create_connection(("127.0.0.1", self._backend))
            server.sendall(connect)
        except OSError:
            client.close()
            return
        dead = [False]
        with self._lock:
            self._open.append((who, dead))
            self._socks += [client, server]
        threading.Thread(target=self._pipe, args=(client, server, [False]), daemon=True).start()
        self._pipe(server, client, dead)

    def _pipe(self, a: socket.socket, b: socket.socket, dead: list[bool]) -> None:
        with contextlib.suppress(OSError):
            while data := a.recv(65536):
                if not dead[0]:
                    b.sendall(data)
        with contextlib.suppress(OSError):
            if not dead[0]:
                b.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self._listener.close()
        for s in self._socks:
            s.close()


@pytest.mark.xfail(
    strict=True,
    reason=(
        "review 114: a STOP only the stop express read while the main connection's path was "
        "dead is dropped for a target that connection read before; the rotor turns on"
    ),
)
def test_an_early_stop_is_carried_out_when_the_main_connections_path_died_after_its_move(
    tmp_path: Path, broker: Mosquitto
) -> None:
    paths = _DeadPaths(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, paths, probe) as rig:
            rig.express = True
            emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            settings = rig.settings.mqtt
            app = rig.start()
            rig.ready("tower")
            wait_until(app.express.up.is_set, 10, "the express up")
            wait_until(lambda: "tower" in app.express.held, 10, "the express holds the port")
            assert probe.publish("rotor/target", "300")  # a long turn (145 s)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            (tmp_path / "words.acl").write_text(f"{OPEN}topic deny {WORDS}\n")
            broker.reload()  # the express's sync words dropped from now on
            start = broker.log.stat().st_size
            app.express.redial()  # its connection new: every word it reads is early
            denied = f"Denied PUBLISH from {express_client_id(settings)}"
            wait_until(
                lambda: denied in broker.log.read_bytes()[start:].decode(errors="replace"),
                15,
                "the express back and subscribed, its word dropped",
            )
            paths.kill({settings.effective_client_id(), lane_client_id(settings)})
            assert probe.publish("rotor/stop", "STOP")  # the operator's STOP
            emu.wait_for(lambda s: not s.is_moving, slow(10))
    finally:
        probe.close()
        paths.close()
