"""COLD REVIEW 25 (f68d30a8), finding R25-3: failed at f68d30a8; the move now carries its
expiry and the session drops it when the hold ends past it (session.py rule 13).

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

from bridge.core.model import Target
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.mqtt.test_review22_lost_lane_copy import controller, markers_back
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator


@pytest.mark.parametrize(
    ("backs", "goes"),
    [
        ((False, False, True), False),  # back 14 s after P was sent: past its 5 s expiry
        ((True,), True),  # back 2 s after: in time, it goes
    ],
)
def test_r25_3_a_stamped_target_waiting_under_a_hold_does_not_go_after_its_expiry(
    backs: tuple[bool, ...], goes: bool
) -> None:
    now = [NOW_UNIX]
    steady = [1000.0]
    pub = RecordingPublisher()
    svc = MqttService(
        Topics("rotor", {"tower": "rotor"}), pub, wall=lambda: now[0], clock=lambda: steady[0]
    )
    tower = RecordingRotator("tower", "rotorez")
    tower.release = lambda marker, *, clear=False: tower.calls.append(  # type: ignore[method-assign]
        ("release", marker, *(["clear"] if clear else []), steady[0])  # (when: the session's)
    )
    svc.attach(tower)
    pub.take()
    # the remote: S, then P 300 (stamped, 5 s expiry), right after it
    svc.on_lane_message("rotor/stop", b"", False)  # S, the lane first: on hold
    svc.on_message("rotor/stop", b"", False)  # its copy on the main connection
    svc.on_message("rotor/target", b"300", False, stamp=Stamp.of(now[0], 5.0))  # fresh: waits
    assert not [c for c in tower.calls if c[0] == "refused"], tower.calls
    handed = [c[1] for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    assert [t.not_after_s for t in handed] == [1005.0]  # its expiry, on the steady clock
    pub.take()  # the marker, and the fresh one sent at the copy, lost (the broker dropped them)
    on_time, _locked = controller(list(tower.calls))  # (at 259f6e04 it went here, at once)
    assert on_time == []
    for wait_s, back in zip((2.0, 4.0, 8.0), backs, strict=False):  # rule 5's back-off
        now[0] += wait_s
        steady[0] += wait_s
        svc._halts.resend_if_due()  # (the timer: a marker sent again)
        if back:
            markers_back(svc, pub)
        else:
            pub.take()  # lost again in the flood
    reached, _locked = controller(tower.calls)
    assert reached == ([300.0] if goes else []), (
        "a target stamped with a 5 s expiry went to the controller after it (it waited under "
        f"the hold, and nothing judged its expiry again), or not in time: {tower.calls}"
    )
