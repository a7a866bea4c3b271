"""Review 122: the demo's look at its MQTT port (bridge/demo/mosquitto.py ``answers``, since
"demo: a broker answers when a CONNECT gets a CONNACK") gives a broker 2 s to send its CONNACK,
and a broker that takes longer is said to speak no MQTT. The bridge itself waits 5 s for one
(bridge/interfaces/mqtt/paho_client.py ``accepts_mqtt311``, paho's connect timeout): a broker
that is slow to let a client in (an authentication plugin asking a server, a loaded Raspberry
Pi, a broker reached through a slow link) serves the bridge and the demo's own console, and
served the demo before that commit. Now the demo tells the user "takes connections but answers
no MQTT (no CONNACK): not a broker" about their working broker, and with
``--no-private-broker`` refuses to run at all (exit 1); without it, it bridges to a private
mosquitto that their Home Assistant cannot see (README: the demo uses the broker at
127.0.0.1:1883 "if one answers ... so it shows up in a Home Assistant on that broker").

Real mosquitto, behind a TCP relay that hands on each connection's first answer from the
broker (its CONNACK) late."""

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
from tests.support.mosquitto import Mosquitto

CONNACK_LATE_S = 3.0  # the broker's own pace, not a deadline: past the demo's 2 s, under paho's 5 s


class SlowBroker:
    """127.0.0.1:``port`` relays to ``backend``; the broker's first bytes on each connection (its
    CONNACK) are handed on ``CONNACK_LATE_S`` late, everything after at once."""

    def __init__(self, backend: int) -> None:
        self._backend = backend
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port: int = self._listener.getsockname()[1]
        self._closed = threading.Event()
        self._socks: list[socket.socket] = []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                client, _ = self._listener.accept()
                server = socket.create_connection(("127.0.0.1", self._backend))
            except OSError:
                return
            self._socks += [client, server]
            threading.Thread(target=self._pipe, args=(client, server, False), daemon=True).start()
            threading.Thread(target=self._pipe, args=(server, client, True), daemon=True).start()

    def _pipe(self, src: socket.socket, dst: socket.socket, late: bool) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                if late:
                    late = False
                    if self._closed.wait(CONNACK_LATE_S):  # the broker's pace (not a deadline)
                        return
                dst.sendall(data)
        with contextlib.suppress(OSError):
            dst.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self._closed.set()
        self._listener.close()
        for s in self._socks:
            s.close()


@pytest.fixture
def slow_broker(broker: Mosquitto) -> Iterator[SlowBroker]:
    relay = SlowBroker(broker.port)
    yield relay
    relay.close()


def test_a_broker_slow_to_connack_is_still_the_demos_broker(
    slow_broker: SlowBroker,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    caplog.set_level(logging.INFO)
    port = slow_broker.port
    args = build_parser().parse_args(
        ["demo", "--mqtt-port", str(port), "--web-port", "0", "--no-private-broker"]
        + ["--duration-s", "12"]
    )
    code = demo.run(args)
    said = capsys.readouterr()
    assert "answers no MQTT" not in said.err, f"the user's broker called no broker: {said.err}"
    assert code == 0, f"the demo refused the user's working broker (exit {code}): {said.err}"
    assert f"the MQTT broker already running at 127.0.0.1:{port}" in said.out, said.out
    assert "connected to MQTT broker" in caplog.text, "the bridge never connected to it"
