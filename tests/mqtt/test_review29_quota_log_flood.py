"""Cold review 29: delivery.py rule 11 now reads only PUBACK 0x87 as the ACL denying a topic;
any other refusal (0x97 quota exceeded, 0x80 a busy broker) "lost this message and says
nothing of the topic", and is logged as a warning, each time, with no bound: a broker under
a publish quota refusing every QoS 1 publish (the rotators' retained state, each move) writes
one warning line per message for as long as it lasts, where rule 13's failed publishes are
said once in FAILED_LOG_S and a denied topic once.
"""

from __future__ import annotations

import logging

import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from tests.mqtt.test_attack5_refused_markers import _delivery


def test_a_quota_refusing_every_publish_is_not_logged_once_per_message(
    caplog: pytest.LogCaptureFixture,
) -> None:
    delivery, paho_client = _delivery()
    for _ in range(1000):  # the rotator's state, at QoS 1, while the quota lasts
        delivery.send("rotor/state", b"moving", 1, retain=True)
    quota = ReasonCode(PacketTypes.PUBACK, "Quota exceeded")
    with caplog.at_level(logging.WARNING, logger="bridge.interfaces.mqtt.delivery"):
        for mid, _topic, _data in paho_client.sent:
            delivery.on_publish(None, None, mid, quota, None)  # type: ignore[arg-type]
    lines = [r for r in caplog.records if "refused a message" in r.getMessage()]
    assert len(lines) <= 2, f"{len(lines)} warnings for one quota"
