"""Review 127: d2c24c97 made the demo's look at its broker step down to MQTT 3.1.1 "as the bridge
connects", so a broker that speaks only MQTT 3.1.1 (nats-server, which answers an MQTT 5 CONNECT
with "Unsupported protocol version"; RabbitMQ 3, amqtt) is now the demo's broker, announced as
"the MQTT broker already running". The bridge steps down and runs; the demo's own console client
(bridge/demo/console.py ``Console``, and ``private_broker_of``) speaks MQTT 5 alone and is
refused for the whole run: nothing the bridge publishes is shown, a typed bearing goes nowhere,
and at its end the demo says "the broker no longer answers, so its retained messages were not
removed (a private broker, ended with the demo, keeps none)" about the user's broker, which
answers and keeps every one: the demo's state topics (13 for one rotator: bridge/state,
availability, bearing, state, ...) stay retained under a base topic no later run will use, and
each run adds 13 more (rule 4: "it removes what it left retained on the broker ... so runs do
not pile up"; README: "However it ends, it removes ... what it left on the broker").

Real nats-server with its MQTT listener; the retained messages read afterwards by an MQTT 3.1.1
client, as a Home Assistant on that broker would."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge import demo
from bridge.cli import build_parser
from tests.support.brokers import Nats, find_nats
from tests.support.waiting import slow


@pytest.fixture
def nats(tmp_path: Path) -> Iterator[Nats]:
    if find_nats() is None:
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    n = Nats(tmp_path / "nats").start()
    yield n
    n.stop()


def retained_on(port: int, topic_filter: str) -> dict[str, bytes]:
    """What a new MQTT 3.1.1 subscriber to ``topic_filter`` gets retained: the messages ahead of
    a marker of its own, published after its subscription."""
    marker = "review127/marker"
    got: dict[str, bytes] = {}
    done = threading.Event()

    def on_connect(client: paho.Client, *_: Any) -> None:
        client.subscribe([(topic_filter, 1), (marker, 1)])

    def on_subscribe(client: paho.Client, *_: Any) -> None:
        client.publish(marker, b"end", qos=1)

    def on_message(client: paho.Client, u: Any, msg: paho.MQTTMessage) -> None:
        if msg.topic == marker:
            done.set()
        elif msg.retain and msg.payload:
            got[msg.topic] = bytes(msg.payload)

    c = paho.Client(CallbackAPIVersion.VERSION2, client_id="review127", protocol=paho.MQTTv311)
    c.on_connect, c.on_subscribe, c.on_message = on_connect, on_subscribe, on_message
    c.connect("127.0.0.1", port)
    c.loop_start()
    try:
        assert done.wait(slow(20)), "the MQTT 3.1.1 reader never got its own marker back"
    finally:
        c.disconnect()
        c.loop_stop()
    return got


def test_a_demo_on_an_mqtt311_broker_leaves_nothing_retained_there(
    nats: Nats,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(work))
    args = build_parser().parse_args(
        ["demo", "--mqtt-port", str(nats.port), "--web-port", "0", "--no-private-broker"]
        + ["--duration-s", "4"]
    )
    code = demo.run(args)
    said = capsys.readouterr()
    assert code == 0, said.err
    assert f"the MQTT broker already running at 127.0.0.1:{nats.port}" in said.out, said.out
    assert "/bearing = " in said.out, f"the console showed no bearing: {said.out[-400:]}"
    left = {
        topic
        for topic in retained_on(nats.port, "#")
        if topic.startswith("rotor-demo-") or "rotorbridge_rotor-demo-" in topic
    }
    assert not left, (
        f"the demo left {len(left)} retained messages on the user's broker: "
        f"{sorted(left)}; it said: {(said.out + said.err)[-300:]}"
    )
