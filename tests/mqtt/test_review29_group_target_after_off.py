"""Cold review 29: a member's lock OFF that waits under a lane hold (lastword.py rule 13) keeps
the newest move of that member read after it, to put after the OFF at the marker, but only its
own topics' moves (``service._command``). A group's target (``G/target``, service.py's fan-out)
asks ``stale_move`` alone, which says AFTER_WAITING_OFF: published lock ON, lock OFF (the
member), then the group's target, the member is refused ("send it again once the lock state
says OFF") where read without a hold it is unlocked and turned; the everyday sequence of
rule 13 (a lock ON, an OFF, a target) refused for a group's member.
"""

from __future__ import annotations

import pytest

from tests.mqtt.test_groups import group_service
from tests.mqtt.test_review22_lost_lane_copy import controller, markers_back


def _turned(lane_first: bool) -> tuple[list[float], bool | None]:
    svc, pub, upper, _lower = group_service()
    if lane_first:
        svc.on_lane_message("rotor/upper/lock", b"ON", False)  # carried at once, on hold
    svc.on_message("rotor/upper/lock", b"ON", False)  # (its copy, counted)
    svc.on_message("rotor/upper/lock", b"OFF", False)
    svc.on_message("rotor/stack/target", b"120", False)
    markers_back(svc, pub)
    return controller(upper.calls)


def test_without_a_hold_the_member_is_unlocked_and_turned() -> None:
    assert _turned(lane_first=False) == ([120.0], False)


@pytest.mark.xfail(
    strict=True,
    reason="review 29: a group target read behind a member's waiting lock OFF is refused "
    "(stale_move: AFTER_WAITING_OFF), not kept behind the OFF as the member's own target is",
)
def test_a_group_target_after_a_members_waiting_lock_off_turns_it_at_the_marker() -> None:
    assert _turned(lane_first=True) == ([120.0], False)
