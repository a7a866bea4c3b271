"""COLD REVIEW 25 (f68d30a8), finding R25-3: FAILS at f68d30a8.

service.py rule 9: a command stamped with its send time and expiry (the remote's, MQTT 5 user
properties; ``command_expiry_s`` 5 s by default) "is refused when it is older than its expiry
... a link that held it up must not turn the rotor late". It is judged once, when the main
connection reads it. Since d32236a1 (lastword.py rule 13) a move read after the count copy of
a lane STOP is not refused and does not go either: it waits in the mailbox under the hold
until the marker comes back, and nothing judges its expiry again. With the marker (and the
fresh one sent at the copy) lost (QoS 0, the broker dropping messages for a reader behind a
flood: the case rule 5's resend exists for), the hold lasts until a resend comes back
(2 s, then 4, 8, 16, 30 s), and the remote's P, sent right after its S, turns the rotor long
after its expiry, when the operator at the remote has given up on it. At 259f6e04 the copy
ended the hold and P went at once.
"""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.mqtt.test_review22_lost_lane_copy import controller, markers_back
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator


@pytest.mark.xfail(
    strict=True,
    reason="review 25 R25-3, open: a stamped move is judged against its expiry when read; "
    "one read after the copy of a lane halt waits for the marker, and with every marker lost "
    "it goes at a resend's return (lastword.py rule 13)",
)
def test_r25_3_a_stamped_target_waiting_under_a_hold_does_not_go_after_its_expiry() -> None:
    now = [NOW_UNIX]
    steady = [1000.0]
    pub = RecordingPublisher()
    svc = MqttService(
        Topics("rotor", {"tower": "rotor"}), pub, wall=lambda: now[0], clock=lambda: steady[0]
    )
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    pub.take()
    # the remote: S, then P 300 (stamped, 5 s expiry), right after it
    svc.on_lane_message("rotor/stop", b"", False)  # S, the lane first: on hold
    svc.on_message("rotor/stop", b"", False)  # its copy on the main connection
    svc.on_message("rotor/target", b"300", False, stamp=Stamp.of(now[0], 5.0))  # fresh: waits
    assert not [c for c in tower.calls if c[0] == "refused"], tower.calls
    pub.take()  # the marker, and the fresh one sent at the copy, lost (the broker dropped them)
    on_time, _locked = controller(list(tower.calls))  # (at 259f6e04 it went here, at once)
    for wait_s, lost in ((2.0, True), (4.0, True), (8.0, False)):  # rule 5's back-off
        now[0] += wait_s
        steady[0] += wait_s
        svc._halts.resend_if_due()  # (the timer: a marker sent again)
        if lost:
            pub.take()  # lost again in the flood
        else:
            markers_back(svc, pub)  # 14 s after P was sent, one comes back
    reached, _locked = controller(tower.calls)
    late = reached[len(on_time) :]
    assert 300.0 not in late, (
        "a target stamped with a 5 s expiry went to the controller 14 s after it was sent (it "
        f"waited under the hold, and nothing judged its expiry again): {tower.calls}"
    )
