"""COLD REVIEW 25 (f68d30a8), finding R25-1, service level: FAILS at f68d30a8.

The service-level twin of tests/integration/test_review25_read_denied_markers.py: the broker
takes every marker (its PUBACK a success: ``markers_refused`` says no) and delivers none back
(a read ACL reloaded under the live connection; mosquitto checks it when it delivers). The
main connection reads the copies of the lane's halts, in order, and what the user published
after them. Since d32236a1 nothing ends a hold whose copy was counted but its marker (rule 13),
and rule 15 needs a refusal that never comes: a lock ON then OFF back to back leaves the
rotator locked for as long as the connection lives (the OFF waits, unsaid), and a STOP then a
target leaves the target waiting, unsaid. At 259f6e04 the copy ended the hold.
"""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.mqtt.test_review22_lost_lane_copy import controller
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator


def _rig() -> tuple[MqttService, RecordingPublisher, RecordingRotator, list[float]]:
    steady = [1000.0]
    pub = RecordingPublisher()
    svc = MqttService(
        Topics("rotor", {"tower": "rotor"}), pub, wall=lambda: NOW_UNIX, clock=lambda: steady[0]
    )
    svc.confirm_markers_with(pub.publish_marker, lambda topics: False)  # PUBACK: success
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    pub.take()
    return svc, pub, tower, steady


def _minutes_of_resends(svc: MqttService, pub: RecordingPublisher, steady: list[float]) -> None:
    for _ in range(20):  # rule 5's resends over ten minutes, none delivered back
        steady[0] += 30.0
        svc._halts.resend_if_due()
        svc._halts._refused_now()
        pub.take()


@pytest.mark.xfail(
    strict=True,
    reason="review 25 R25-1, open: markers the broker takes but never delivers back (a read "
    "ACL reloaded under a live connection; nothing from the broker says it) end no hold whose "
    "copy was counted: it lasts until the main connection drops, said on B/bridge/info "
    "(lastword.py rule 15; mosquitto grants a SUBSCRIBE to them again, so asking again says "
    "nothing either); ending it on a timer is what rule 5 forbids",
)
def test_r25_1_lock_on_then_off_back_to_back_ends_off_though_no_marker_is_delivered() -> None:
    svc, pub, tower, steady = _rig()
    svc.on_lane_message("rotor/lock", b"ON", False)  # the lane first: carried out, on hold
    svc.on_message("rotor/lock", b"ON", False)  # its copy
    svc.on_message("rotor/lock", b"OFF", False)  # the last word
    pub.take()  # the markers: taken by the broker, never delivered
    _minutes_of_resends(svc, pub, steady)
    assert controller(tower.calls)[1] is False, (
        "lock ON then OFF, back to back, ten minutes ago: the rotator is still locked (the OFF "
        f"waits for a marker that is never delivered; nothing said): {tower.calls}"
    )


@pytest.mark.xfail(
    strict=True,
    reason="review 25 R25-1, open: markers the broker takes but never delivers back (a read "
    "ACL reloaded under a live connection; nothing from the broker says it) end no hold whose "
    "copy was counted: it lasts until the main connection drops, said on B/bridge/info "
    "(lastword.py rule 15; mosquitto grants a SUBSCRIBE to them again, so asking again says "
    "nothing either); ending it on a timer is what rule 5 forbids",
)
def test_r25_1_stop_then_target_back_to_back_reaches_the_target_though_no_marker_comes() -> None:
    svc, pub, tower, steady = _rig()
    svc.on_lane_message("rotor/stop", b"", False)
    svc.on_message("rotor/stop", b"", False)
    svc.on_message("rotor/target", b"300", False)
    pub.take()
    _minutes_of_resends(svc, pub, steady)
    reached, _locked = controller(tower.calls)
    assert reached == [300.0], (
        "STOP then target 300, back to back, ten minutes ago: the target never went (it "
        f"waits under a hold only a marker ends; nothing said): {tower.calls}"
    )
