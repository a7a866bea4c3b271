"""Review 35 (the refused hello of db50b34f's case): the look's hello goes out with paho's own
publish (client.py ``_opened``), at QoS 1, its message id noted by nobody. Refused by the
broker's ACL (PUBACK 0x87), delivery.py keeps the refusal under that id as "acknowledged before
its id was noted" (``_acked_early``), for a ``send`` to claim, and none does: it stays for the
connection's life. paho's message ids wrap at 65,535 (every publish takes one, a QoS 0 status
too), and the ``send`` that is given the hello's id again, hours later, claims the refusal as
its own: its topic is said denied by the broker's ACL ("not authorized", logged as an error,
on ``B/bridge/info`` and the rotator's status), a topic the broker never refused.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import pytest

from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.client import LOOK_MAX_S, MqttClient
from bridge.settings import MqttSettings
from tests.support import slow, wait_until
from tests.support.mosquitto import Mosquitto

HELLO, ERROR = "rotor/bridge/hello", "rotor/tower/error"


def test_a_refused_hello_is_never_taken_for_a_later_message_s_refusal(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    acl = tmp_path / "acl"
    acl.write_text(f"topic readwrite rotor/#\ntopic deny {HELLO}\n")
    # started as root, mosquitto would become user "mosquitto", who cannot read pytest's tmp
    broker = Mosquitto(
        tmp_path / "broker", extra_conf=f"allow_anonymous true\nacl_file {acl}\nuser root"
    )
    broker.start()
    denied: list[str] = []
    client = MqttClient(
        MqttSettings(port=broker.port, base_topic="rotor", client_id="rev35h", protocol="5"),
        will_topic="rotor/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        on_denied=lambda topic, problem: denied.append(topic),
        claim=Claim(Instance.me("rev35h"), "rotor", "rotor/bridge/info", HELLO),
    )
    paho_client = client._client  # noqa: SLF001
    ids: dict[str, int] = {}  # the message id each topic's last publish was given
    publish = paho_client.publish

    def noting(topic: str, *args: Any, **kwargs: Any) -> Any:
        info = publish(topic, *args, **kwargs)
        ids[topic] = info.mid
        return info

    paho_client.publish = noting  # type: ignore[method-assign]
    try:
        client.start()
        wait_until(client.connected.is_set, slow(LOOK_MAX_S), "the look's end")
        # every PUBACK of what the open sent has come (``online`` takes the id after the
        # hello's: still out, paho refuses the id to the next message, ERR_QUEUE_SIZE)
        opened = paho_client.publish("rotor/sync", b"", qos=1)
        opened.wait_for_publish(slow(5))
        assert opened.is_published()
        # 65,535 publishes later (a turning rotor's statuses, a day's events): paho's next id is
        # the hello's again
        paho_client._last_mid = ids[HELLO] - 1  # noqa: SLF001
        with caplog.at_level(logging.ERROR, logger="bridge.interfaces.mqtt.delivery"):
            client.publish_event(ERROR, '{"error": "a harmless event"}')
            sync = paho_client.publish("rotor/sync", b"", qos=1)
            sync.wait_for_publish(slow(5))
            assert sync.is_published()
        said = [r.getMessage() for r in caplog.records if ERROR in r.getMessage()]
        assert not said and ERROR not in denied, (
            f"the broker took every message on {ERROR}, and the bridge said it refused it: {said}"
        )
    finally:
        client.stop()
        broker.stop()
