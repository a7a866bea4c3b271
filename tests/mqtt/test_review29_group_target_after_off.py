"""Cold review 29: a member's lock OFF that waits under a lane hold (lastword.py rule 13) keeps
the newest move of that member read after it, to put after the OFF at the marker, but only its
own topics' moves (``service._command``). A group's target (``G/target``, service.py's fan-out)
asked ``stale_move`` alone, which says AFTER_WAITING_OFF: published lock ON, lock OFF (the
member), then the group's target, the member was refused ("send it again once the lock state
says OFF") where read without a hold it is unlocked and turned; the everyday sequence of
rule 13 (a lock ON, an OFF, a target) refused for a group's member. Now the member's part is
that member's own target: kept in its slot behind the OFF, replaced by a newer move, dropped by
a STOP or a lock ON as its own kept move is; a member with no OFF waiting turns at once.
"""

from __future__ import annotations

import json
import time

from bridge.core.model import Target
from bridge.interfaces.mqtt.halts import AFTER_OFF_REFUSED, LOCK_OFF_SUPERSEDED
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from tests.mqtt.test_groups import group_service
from tests.mqtt.test_review22_lost_lane_copy import controller, markers_back
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator

GROUP_120 = "target '120' (group stack)"


def _waiting(
    lane_first: bool = True,
) -> tuple[MqttService, RecordingPublisher, RecordingRotator, RecordingRotator]:
    """lock ON (the lane first: carried at once, on hold), its copy, lock OFF on the upper
    rotor (waiting for the marker), then the group's target."""
    svc, pub, upper, lower = group_service()
    if lane_first:
        svc.on_lane_message("rotor/upper/lock", b"ON", False)  # carried at once, on hold
    svc.on_message("rotor/upper/lock", b"ON", False)  # (its copy, counted)
    svc.on_message("rotor/upper/lock", b"OFF", False)
    svc.on_message("rotor/stack/target", b"120", False)
    return svc, pub, upper, lower


def _turned(lane_first: bool) -> tuple[list[float], bool | None]:
    svc, pub, upper, _lower = _waiting(lane_first)
    markers_back(svc, pub)
    return controller(upper.calls)


def _refused(rot: RecordingRotator) -> list[tuple[object, object]]:
    return [(c[1], c[2]) for c in rot.calls if c[0] == "refused"]


def _group_errors(pub: RecordingPublisher) -> list[dict[str, object]]:
    return [json.loads(p) for t, p, _r in pub.sent if t == "rotor/stack/error"]  # (not taken)


def test_without_a_hold_the_member_is_unlocked_and_turned() -> None:
    assert _turned(lane_first=False) == ([120.0], False)


def test_a_group_target_after_a_members_waiting_lock_off_turns_it_at_the_marker() -> None:
    assert _turned(lane_first=True) == ([120.0], False)


def test_the_member_waits_locked_the_other_turns_at_once_and_nothing_is_refused() -> None:
    svc, pub, upper, lower = _waiting()
    assert controller(upper.calls) == ([], True)  # (not unlocked, not moved before the marker)
    assert controller(lower.calls) == ([300.0], None)  # no OFF waits for it: as ever
    assert _refused(upper) == [] and _group_errors(pub) == []
    markers_back(svc, pub)
    kept = [c for c in upper.calls if c[0] == "submit" and isinstance(c[1], Target)]
    assert [c[2] for c in kept] == [GROUP_120]  # (said as the group's, in its audit trail)
    assert _refused(upper) == []


def test_a_stop_on_the_member_after_it_drops_it_and_leaves_the_off() -> None:
    svc, pub, upper, _lower = _waiting()
    svc.on_message("rotor/upper/stop", b"", False)  # published after the group's target
    markers_back(svc, pub)
    assert controller(upper.calls) == ([], False), upper.calls
    assert _refused(upper) == []  # (a STOP drops what was before it, as its own target's)


def test_a_stop_on_the_group_after_it_drops_it_and_leaves_the_off() -> None:
    svc, pub, upper, lower = _waiting()
    svc.on_message("rotor/stack/stop", b"", False)
    markers_back(svc, pub)
    assert controller(upper.calls) == ([], False), upper.calls
    assert _refused(upper) == []


def test_a_stop_on_the_groups_lane_after_it_drops_it() -> None:
    svc, pub, upper, _lower = _waiting()
    svc.on_lane_message("rotor/stack/stop", b"", False)  # carried at once, a new hold
    svc.on_message("rotor/stack/stop", b"", False)  # its copy
    markers_back(svc, pub)
    assert controller(upper.calls)[0] == [], upper.calls


def test_a_lock_on_after_it_drops_it_and_the_off_said_on_the_members_error() -> None:
    svc, pub, upper, _lower = _waiting()
    svc.on_message("rotor/upper/lock", b"ON", False)  # the later word
    markers_back(svc, pub)
    assert controller(upper.calls) == ([], True), upper.calls
    assert _refused(upper) == [
        (LOCK_OFF_SUPERSEDED, "lock OFF"),
        (AFTER_OFF_REFUSED, GROUP_120),
    ]


def test_a_newer_own_target_replaces_it_in_the_one_slot() -> None:
    svc, pub, upper, _lower = _waiting()
    svc.on_message("rotor/upper/target", b"200", False)
    markers_back(svc, pub)
    assert controller(upper.calls) == ([200.0], False), upper.calls
    assert _refused(upper) == []


def test_a_newer_group_target_replaces_an_own_target_kept_before_it() -> None:
    svc, pub, upper, lower = _waiting()
    svc.on_message("rotor/upper/target", b"200", False)
    svc.on_message("rotor/stack/target", b"130", False)
    assert len(svc._halts._after_off) == 1  # noqa: SLF001 (one move kept, the newest)
    markers_back(svc, pub)
    assert controller(upper.calls) == ([130.0], False), upper.calls
    assert controller(lower.calls)[0] == [300.0, 310.0]


def test_a_member_part_stamped_before_its_last_halt_is_refused_not_kept() -> None:
    """service.py rule 9 first, as for the member's own target (on_message judges the stamp
    before ``_command`` keeps it)."""
    svc, pub, upper, lower = group_service()
    svc.on_lane_message("rotor/upper/lock", b"ON", False)
    svc.on_message("rotor/upper/lock", b"ON", False)
    svc.on_message("rotor/upper/lock", b"OFF", False)
    upper.halted_s = time.monotonic() - 1.0  # its lock ON came a second ago
    svc.on_message("rotor/stack/target", b"120", False, stamp=Stamp.of(NOW_UNIX - 2.0, 5))
    (refusal,) = _refused(upper)
    assert "before the last STOP or lock ON" in str(refusal[0]) and refusal[1] == GROUP_120
    (error,) = _group_errors(pub)
    assert "before the last STOP" in str(error["members"]["upper"])  # type: ignore[index]
    markers_back(svc, pub)
    assert controller(upper.calls) == ([], False), upper.calls
    assert controller(lower.calls)[0] == [300.0]


def test_a_stamped_group_target_kept_behind_the_off_keeps_its_expiry() -> None:
    """service.py rule 9, session.py rule 13: the member's part kept in its slot carries the
    group target's expiry on the steady clock, as the part put at once does; the session
    drops it if the marker comes back past it."""
    svc, pub, upper, lower = group_service()
    svc.on_lane_message("rotor/upper/lock", b"ON", False)
    svc.on_message("rotor/upper/lock", b"ON", False)
    svc.on_message("rotor/upper/lock", b"OFF", False)
    before = time.monotonic()
    svc.on_message("rotor/stack/target", b"120", False, stamp=Stamp.of(NOW_UNIX, 5.0))
    after = time.monotonic()
    markers_back(svc, pub)
    for rot in (upper, lower):
        sent = [c[1] for c in rot.calls if c[0] == "submit" and isinstance(c[1], Target)]
        assert len(sent) == 1, rot.calls
        ends = sent[0].not_after_s
        assert ends is not None and before + 5.0 <= ends <= after + 5.0, (rot.id, ends)
