"""Attack pass 5 on lastword.py rule 15: "both topics refused, the markers are known denied
(rule 7), and a hold whose copy was counted ends". What counts as refused is delivery.py's
``denied``: *any* failing PUBACK reason code (``reason_code.is_failure``), not the ACL's 0x87
"Not authorized". A flaky or loaded broker that answers the two resent markers' PUBACKs with
0x97 "Quota exceeded" (EMQX, HiveMQ under a publish quota), 0x80 "Unspecified error" or 0x83
"Implementation specific error" is taken for an ACL that denies the markers: markers off for
the rest of the connection (nothing allows them again until a new one), the copied holds end
at once, and from then on the count copy ends holds again: rule 13's gap (a target
published between an older STOP the lane lost and the lane's newer STOP goes after the newer
STOP) is open for as long as the connection lives.
"""

from __future__ import annotations

import itertools
from types import SimpleNamespace

from paho.mqtt.enums import MQTTErrorCode
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from bridge.interfaces.mqtt.delivery import Delivery
from tests.mqtt.test_review22_lost_lane_copy import controller
from tests.mqtt.test_service import RecordingRotator, saying_service


class FakePaho:
    def __init__(self) -> None:
        self.mids = itertools.count(1)
        self.sent: list[tuple[int, str, bytes | str]] = []

    def publish(self, topic: str, data: bytes | str, qos: int = 0, retain: bool = False):  # type: ignore[no-untyped-def]
        mid = next(self.mids)
        self.sent.append((mid, topic, data))
        return SimpleNamespace(rc=MQTTErrorCode.MQTT_ERR_SUCCESS, mid=mid)


def _delivery() -> tuple[Delivery, FakePaho]:
    paho_client = FakePaho()
    delivery = Delivery(paho_client, username="bridge", report=lambda t, p: None, clock=lambda: 0.0)  # type: ignore[arg-type]
    return delivery, paho_client


def test_a_quota_exceeded_puback_is_not_taken_for_an_acl_denying_the_markers() -> None:
    delivery, paho_client = _delivery()
    topics = ("rotor/bridge/fence", "rotor/bridge/hello")
    for topic in topics:  # the marker sent again at QoS 1 (halts.py publish_confirmed)
        delivery.send(topic, b"marker", 1, retain=False)
    quota = ReasonCode(PacketTypes.PUBACK, "Quota exceeded")
    for mid, _topic, _data in paho_client.sent:
        delivery.on_publish(None, None, mid, quota, None)  # type: ignore[arg-type]
    refused = all(delivery.denied(t) for t in topics)  # client.py markers_refused
    assert not refused, (
        "0x97 'Quota exceeded' on the resent markers' PUBACKs is read as the broker's ACL "
        "refusing both marker topics (lastword.py rule 15): markers off for the connection"
    )


def test_a_transient_puback_error_does_not_reopen_the_lost_lane_copy_gap() -> None:
    """Published: STOP 1, target 300, STOP 2. The lane lost STOP 1 and read STOP 2 (carried
    out). The main connection reads STOP 1 (counted as STOP 2's copy), is slow to read on
    (a backlog); the marker is sent again at QoS 1, and a loaded broker answers its two
    PUBACKs 0x97. The target 300, read next, must not reach the controller after STOP 2."""
    clock, _said, pub, svc = saying_service()
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    delivery, paho_client = _delivery()
    svc.confirm_markers_with(
        lambda topic, payload: delivery.send(topic, payload.encode(), 1, retain=False),
        lambda topics: all(delivery.denied(t) for t in topics),
    )
    svc.on_lane_message("rotor/stop", b"", False)  # STOP 2 on the lane: carried, hold
    svc.on_message("rotor/stop", b"", False)  # STOP 1 on the main one: the count copy
    for _ in range(10):  # the main connection reads nothing for a while (a backlog)
        clock.t += 1.0
        svc._halts.resend_if_due()  # noqa: SLF001 (the timer's work, halts._tick)
        svc._halts._refused_now()  # noqa: SLF001
        quota = ReasonCode(PacketTypes.PUBACK, "Quota exceeded")
        for mid, _topic, _data in paho_client.sent:
            delivery.on_publish(None, None, mid, quota, None)  # type: ignore[arg-type]
        paho_client.sent.clear()
    svc.on_message("rotor/target", b"300", False)  # published before STOP 2
    reached, _locked = controller(tower.calls)
    svc.on_message("rotor/stop", b"", False)  # STOP 2's real copy, too late
    assert reached == [], (
        "a target published before the lane's STOP reached the controller after it: two "
        f"PUBACKs 0x97 'Quota exceeded' were taken for the markers denied: {tower.calls}"
    )
