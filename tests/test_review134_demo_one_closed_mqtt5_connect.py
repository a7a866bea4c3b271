"""Review 134, finding 2: since 343a5337 the demo's look (bridge/demo/mosquitto.py
``connack_of``) says which protocol its broker speaks, and a single MQTT 5 CONNECT closed before
its CONNACK, then a 3.1.1 one answered, is taken for "MQTT 3.1.1 alone" for the whole run. A
close is also a broker restarting, a connection limit or anyone on the path: the bridge's own
step-down never takes one close as evidence (tests/integration/test_broker_fallback.py
``test_a_close_alone_never_steps_down``, "came back speaking 5"). On such a broker the demo
says "(it speaks MQTT 3.1.1, not 5)" of an MQTT 5 broker, runs its console in 3.1.1 and skips
rule 5's question (``private_broker_of`` is asked only on MQTT 5): another demo's private
mosquitto is taken for the user's broker, and the demo's bridge loses its broker for good when
that other demo ends (test_demo.py ``test_a_second_demo_keeps_turning_after_the_first...``).
The parent asked ``private_broker_of`` whatever the look's protocol, and said none.

Real mosquitto carrying another demo's mark (as bridge/demo/console.py rule 5 leaves it),
behind the project's relay that closes the first MQTT 5 CONNECT only (a restart)."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge.demo.console import PRIVATE_BROKER_MARK
from tests.demo_process import run_demo_in_process
from tests.support.brokers import NoMqtt5
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow


@pytest.fixture
def restarted(broker: Mosquitto) -> Iterator[NoMqtt5]:
    relay = NoMqtt5(broker.port)
    relay.v5_closes_left = 1  # one MQTT 5 connection closed, then MQTT 5 as ever
    yield relay
    relay.close()


def mark_as_another_demos(port: int, instance: str) -> None:
    connected = threading.Event()

    def on_connect(client: paho.Client, *_: Any) -> None:
        connected.set()

    c = paho.Client(CallbackAPIVersion.VERSION2, client_id="r134other", protocol=paho.MQTTv5)
    c.on_connect = on_connect
    c.connect("127.0.0.1", port)
    c.loop_start()
    try:
        assert connected.wait(slow(20)), "the other demo's stand-in never connected"
        c.publish(PRIVATE_BROKER_MARK, instance.encode(), qos=1, retain=True).wait_for_publish(
            slow(10)
        )
    finally:
        c.disconnect()
        c.loop_stop()


def test_one_closed_mqtt5_connect_does_not_hide_another_demos_private_broker(
    broker: Mosquitto,
    restarted: NoMqtt5,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    mark_as_another_demos(broker.port, "zz99")
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    code = run_demo_in_process(restarted.port, "--duration-s", "2")
    said = capsys.readouterr()
    assert code == 0, said.err
    assert "speaks MQTT 3.1.1, not 5" not in said.out, said.out[:400]
    assert f"the one on 127.0.0.1:{restarted.port} is demo zz99's" in said.out, said.out[:400]
