"""Review 146, finding 5: since 9b73f8b9 the demo's console (bridge/demo/console.py rule 6) says
"held" of a STOP typed while it knows it has lost the broker (review 144 (4)), but it learns so
only in on_disconnect: paho first closes its socket (``_sock_close``: ``_sock`` None), then calls
on_disconnect. A STOP typed in between passes the console's ``connected`` check, paho takes it
without a connection (MQTT_ERR_NO_CONN, kept for the next one) and the console prints nothing:
if the broker does not come back, the STOP never goes and the user who typed ``s`` at a turning
rotor was told nothing (review 144 (4)'s silence, left open in this window). Older: its parent
1998b9a5 said nothing of any STOP typed while cut off.

Real nats-server (MQTT 3.1.1); the console's connection through review 134's relay, cut and kept
refusing; the user types ``s`` (on a thread of their own, as the demo's input thread) while paho
closes the socket (paho's on_socket_close, called there with the socket already gone, widened
till the STOP is typed).

Fixed: console.py rule 6."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.interfaces.mqtt.topics import Topics
from tests.support.brokers import Nats, find_nats
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import (
    BASE,
    Cuttable,
    console_through,
)


@pytest.fixture
def nats(tmp_path: Path) -> Iterator[Nats]:
    if find_nats() is None:
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    n = Nats(tmp_path / "nats").start()
    yield n
    n.stop()


def test_a_stop_typed_as_the_console_loses_the_broker_is_said_not_gone_yet(
    nats: Nats, capsys: pytest.CaptureFixture[str]
) -> None:
    relay = Cuttable(nats.port)
    topics = Topics(BASE, {"rotorez": BASE})
    console = console_through(relay.port, topics, mqtt5=False)
    typed = threading.Event()

    def on_socket_close(client: Any, userdata: Any, sock: Any) -> None:
        if not typed.is_set():
            user = threading.Thread(target=console.command, args=("s",))
            user.start()
            user.join(slow(20))
            typed.set()

    try:
        assert console.sync(slow(20)), "the MQTT 3.1.1 console never connected through the relay"
        tries = len(relay.levels)
        capsys.readouterr()
        console._client.on_socket_close = on_socket_close
        relay.cut()  # the broker gone, and staying gone
        wait_until(lambda: len(relay.levels) > tries, 20, "the console trying to reconnect")
        said = capsys.readouterr().out
    finally:
        console.close()
        relay.close()
    assert typed.is_set(), "paho never closed its socket"
    assert "STOP" in said, f"the console said nothing of the STOP it could not send: {said!r}"
