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
from collections.abc import Callable
from types import SimpleNamespace

from paho.mqtt.enums import MQTTErrorCode
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from bridge.core.model import Target
from bridge.interfaces.mqtt.delivery import Delivery
from bridge.interfaces.mqtt.halts import FENCED
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


class ConfirmedRig:
    """A service whose markers sent again go at QoS 1 through a real Delivery (lastword.py rule
    15), the broker's PUBACKs answered by the test, the halts timer's work run by hand."""

    def __init__(self) -> None:
        self.clock, self.said, self.pub, self.svc = saying_service()
        self.tower = RecordingRotator("tower", "rotorez")
        self.svc.attach(self.tower)
        self.delivery, self.paho = _delivery()
        self.svc.confirm_markers_with(
            lambda topic, payload: self.delivery.send(topic, payload.encode(), 1, retain=False),
            lambda topics: all(self.delivery.denied(t) for t in topics),
        )

    def run(self, seconds: int, code: str | Callable[[str], str], back: bool = False) -> None:
        """``seconds`` of the timer (halts._tick), each marker sent at QoS 1 answered ``code``
        (or ``code(topic)``); ``back``: the markers published come back on the main
        connection (those sent at QoS 1 that the broker took too)."""
        halts = self.svc._halts  # noqa: SLF001
        for _ in range(seconds):
            self.clock.t += 1.0
            halts.resend_if_due()
            halts._refused_now()  # noqa: SLF001
            taken: list[tuple[str, bytes | str]] = []
            for mid, topic, data in self.paho.sent:
                reason = code if isinstance(code, str) else code(topic)
                ack = ReasonCode(PacketTypes.PUBACK, reason)
                self.delivery.on_publish(None, None, mid, ack, None)  # type: ignore[arg-type]
                if not ack.is_failure:
                    taken.append((topic, data))
            self.paho.sent.clear()
            if back:
                for topic, data in taken:
                    if topic in ("rotor/bridge/fence", "rotor/bridge/hello"):
                        payload = data if isinstance(data, bytes) else data.encode()
                        self.svc.on_message(topic, payload, False)
                for topic, payload, _retain in self.pub.take():
                    if topic in ("rotor/bridge/fence", "rotor/bridge/hello"):
                        self.svc.on_message(topic, payload.encode(), False)

    def fenced_against_rotctlds_stop(self) -> tuple[bool, list[tuple[object, ...]]]:
        """rotctld's S, then a target published before it, read late (behind a flood of
        targets): whether the target was refused as fenced (lastword.py rule 11, which the
        markers make possible), and what the rotator was handed meanwhile."""
        self.tower.calls.clear()
        self.svc.fence_asked("tower")
        self.svc.fence_carried("tower", lock=False)
        self.svc.on_message("rotor/target", b"300", False)
        calls = self.tower.calls
        moved = [c for c in calls if c[0] == "submit" and isinstance(c[1], Target)]
        return not moved and ("refused", FENCED, "target '300'") in calls, calls


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
    rig = ConfirmedRig()
    svc, tower = rig.svc, rig.tower
    svc.on_lane_message("rotor/stop", b"", False)  # STOP 2 on the lane: carried, hold
    svc.on_message("rotor/stop", b"", False)  # STOP 1 on the main one: the count copy
    rig.run(10, "Quota exceeded")  # the main connection reads nothing for a while (a backlog)
    svc.on_message("rotor/target", b"300", False)  # published before STOP 2
    reached, _locked = controller(tower.calls)
    svc.on_message("rotor/stop", b"", False)  # STOP 2's real copy, too late
    assert reached == [], (
        "a target published before the lane's STOP reached the controller after it: two "
        f"PUBACKs 0x97 'Quota exceeded' were taken for the markers denied: {tower.calls}"
    )
