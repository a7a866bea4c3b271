"""Review 127: a broker that bans the demo (its CONNACK says 0x8A "banned": EMQX's banned list
and its flapping detection answer an MQTT 5 CONNECT so, keyed by the client's address) is taken
by the demo for its broker. bridge/demo/__init__.py rule 8 makes a refusal of the demo's login
"not its broker" (LOGIN_REFUSED: 0x86, 0x87, 0x8C, 3.1.1's 4 and 5), but ``connack`` returns any
other code as a broker that answers: the banner says "bridged to the MQTT broker already
running", prints ``mosquitto_pub`` lines, and the bridge logs "MQTT broker refused the
connection: Banned (retrying)" for as long as the demo runs: a demo running dead, the case rule 8
was written against. With ``--no-private-broker`` it should end saying the broker refuses it.

A scripted broker: a TCP server that answers every CONNECT with the CONNACK a broker gives a
banned client (MQTT 5: reason code 0x8A; MQTT 3.1.1: 5, "not authorized")."""

from __future__ import annotations

import contextlib
import socket
import threading
from pathlib import Path

import pytest

from bridge import demo
from bridge.cli import build_parser

BANNED_5 = bytes([0x20, 3, 0, 0x8A, 0])  # CONNACK: no session, "banned", no properties
NOT_AUTHORIZED_311 = bytes([0x20, 2, 0, 5])


class BanningBroker:
    def __init__(self) -> None:
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port: int = self._listener.getsockname()[1]
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self._listener.accept()
            except OSError:
                return
            threading.Thread(target=self._answer, args=(conn,), daemon=True).start()

    @staticmethod
    def _answer(conn: socket.socket) -> None:
        with conn, contextlib.suppress(OSError):
            got = b""
            while len(got) < 9 and (chunk := conn.recv(64)):
                got += chunk
            if len(got) >= 9:  # fixed header, protocol name: the level is the 9th byte
                conn.sendall(BANNED_5 if got[8] == 5 else NOT_AUTHORIZED_311)
            while conn.recv(64):  # until the client closes (a broker closes after a refusal,
                pass  # some only once the client has read it)

    def close(self) -> None:
        self._listener.close()


def test_a_broker_that_bans_the_demo_ends_a_demo_told_to_start_no_broker_saying_so(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    broker = BanningBroker()
    try:
        args = build_parser().parse_args(
            ["demo", "--mqtt-port", str(broker.port), "--web-port", "0", "--no-private-broker"]
            + ["--duration-s", "2"]
        )
        code = demo.run(args)
    finally:
        broker.close()
    said = capsys.readouterr()
    assert "bridged to" not in said.out, f"announced a broker that bans it: {said.out[:300]}"
    assert code == 1, said.err
    assert f"127.0.0.1:{broker.port}" in said.err, said.err
