"""Review 122: since "demo: a broker answers when a CONNECT gets a CONNACK", the demo's look at
its MQTT port (bridge/demo/mosquitto.py ``answers``) is an MQTT 3.1.1 CONNECT only. A broker
listener that speaks MQTT 5 alone (rumqttd's v5 listener, a broker set to MQTT 5) closes such a
connection without a CONNACK (MQTT 5 spec 3.1.2.2: it MAY send a CONNACK, then MUST close), and
the demo says of it "takes connections but answers no MQTT (no CONNACK): not a broker"; with
``--no-private-broker`` it refuses to run (exit 1), without it it bridges to a private mosquitto
that Home Assistant on that broker cannot see. The bridge and the demo's console connect with
MQTT 5 first and work on it, as the demo did before that commit.

Real mosquitto, behind a relay that closes every CONNECT that is not MQTT 5."""

from __future__ import annotations

import contextlib
import logging
import socket
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge import demo
from bridge.cli import build_parser
from tests.support.brokers import protocol_level
from tests.support.mosquitto import Mosquitto


class Mqtt5Only:
    """127.0.0.1:``port`` in front of ``backend``: a CONNECT that is not MQTT 5 is answered by
    closing the socket; an MQTT 5 one is passed through, both ways."""

    def __init__(self, backend: int) -> None:
        self._backend = backend
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port: int = self._listener.getsockname()[1]
        self.levels: list[int | None] = []
        self._socks: list[socket.socket] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                sock, _ = self._listener.accept()
            except OSError:
                return
            self._socks.append(sock)
            threading.Thread(target=self._serve, args=(sock,), daemon=True).start()

    def _serve(self, sock: socket.socket) -> None:
        head = b""
        level: int | None = None
        with contextlib.suppress(OSError):
            while level is None and len(head) < 4096 and (data := sock.recv(4096)):
                head += data
                level = protocol_level(head)
        self.levels.append(level)
        if level != 5:
            sock.close()
            return
        up = socket.create_connection(("127.0.0.1", self._backend))
        self._socks.append(up)
        up.sendall(head)
        threading.Thread(target=self._pipe, args=(up, sock), daemon=True).start()
        self._pipe(sock, up)

    def _pipe(self, src: socket.socket, dst: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                dst.sendall(data)
        for s in (src, dst):
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)

    def close(self) -> None:
        self._listener.close()
        for s in self._socks:
            with contextlib.suppress(OSError):
                s.close()


@pytest.fixture
def mqtt5_only(broker: Mosquitto) -> Iterator[Mqtt5Only]:
    relay = Mqtt5Only(broker.port)
    yield relay
    relay.close()


def test_a_broker_that_speaks_only_mqtt5_is_still_the_demos_broker(
    mqtt5_only: Mqtt5Only,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    caplog.set_level(logging.INFO)
    port = mqtt5_only.port
    args = build_parser().parse_args(
        ["demo", "--mqtt-port", str(port), "--web-port", "0", "--no-private-broker"]
        + ["--duration-s", "6"]
    )
    code = demo.run(args)
    said = capsys.readouterr()
    assert "answers no MQTT" not in said.err, f"the user's broker called no broker: {said.err}"
    assert code == 0, f"the demo refused the user's working broker (exit {code}): {said.err}"
    assert f"the MQTT broker already running at 127.0.0.1:{port}" in said.out, said.out
    assert "connected to MQTT broker (MQTT 5" in caplog.text, caplog.text[-600:]
