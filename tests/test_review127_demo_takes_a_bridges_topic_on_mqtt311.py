"""Review 127: bridge/demo/__init__.py rule 4 refuses a ``--base-topic`` that a bridge uses
(``<base>/bridge/state`` retained), reading it through the demo's console client. On a broker
that speaks only MQTT 3.1.1 (nats-server; since d2c24c97 the demo's look steps down to 3.1.1 and
takes such a broker for its own) that client, MQTT 5 alone, is refused and reads nothing, so the
check finds no bridge and the demo runs its bridge on the real bridge's base topic, its banner
saying "a real bridge's are not touched". It replaces the real bridge's Home Assistant devices
with "Demo rotorez (...)" ones under the same node ids and, at its end, leaves
``<base>/bridge/state`` retained "offline": the real bridge, still running, is shown offline
(its Home Assistant entities unavailable) until it next publishes its state. (The real rotator's
retained safety lock ON survives: the demo's bridge heard it and kept it.)

Real nats-server; a real bridge's retained state stands in as an MQTT 3.1.1 client publishes
it; read back the same way."""

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
from tests.test_review127_demo_on_an_mqtt311_broker import retained_on


@pytest.fixture
def nats(tmp_path: Path) -> Iterator[Nats]:
    if find_nats() is None:
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    n = Nats(tmp_path / "nats").start()
    yield n
    n.stop()


def publish_retained(port: int, messages: dict[str, bytes]) -> None:
    """As the real bridge left them: retained, over MQTT 3.1.1, each acknowledged."""
    connected = threading.Event()

    def on_connect(client: paho.Client, *_: Any) -> None:
        connected.set()

    c = paho.Client(CallbackAPIVersion.VERSION2, client_id="realbridge", protocol=paho.MQTTv311)
    c.on_connect = on_connect
    c.connect("127.0.0.1", port)
    c.loop_start()
    try:
        assert connected.wait(slow(20)), "the stand-in for the real bridge never connected"
        for topic, payload in messages.items():
            c.publish(topic, payload, qos=1, retain=True).wait_for_publish(slow(10))
    finally:
        c.disconnect()
        c.loop_stop()


def test_a_demo_on_an_mqtt311_broker_refuses_a_base_topic_a_bridge_uses(
    nats: Nats,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    real = {"shack/bridge/state": b"online", "shack/lock/state": b"ON"}
    publish_retained(nats.port, real)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(work))
    args = build_parser().parse_args(
        ["demo", "--mqtt-port", str(nats.port), "--web-port", "0", "--no-private-broker"]
        + ["--base-topic", "shack", "--duration-s", "2"]
    )
    code = demo.run(args)
    said = capsys.readouterr()
    after = retained_on(nats.port, "shack/#")
    assert {t: after.get(t) for t in real} == real, (
        f"the demo (exit {code}) changed the real bridge's retained state: "
        f"{ {t: after.get(t) for t in real} }; it said: {said.out[:200]}"
    )
    assert code == 2 and "belongs to a bridge" in said.err, said.err
