"""A group's limits on a member's way (pointing.py rule 9) when the bridge cannot see where the
rotor is: a DCU-1 (it never answers) mounted south-centred (``az_offset_deg = 180``: its scale's
stop is at true south, so a turn on its scale can pass true north). In group ``stack`` with
``limits = { upper = [20, 340] }`` the upper antenna must stay out of 340..20 (docs/groups.md: "A
member's limits in the group hold on its way too ... a member whose only way there leaves
them refuses its part"). Without a reading the bridge cannot tell which way the turn goes: the
part must be refused, not sent."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import Target
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_a_group_target_with_limits_is_refused_where_no_reading_shows_the_way(rig: Rig) -> None:
    # the antenna points true 300 (raw 120); the group's 30 is raw 210: 120 -> 210 on the
    # controller's scale is true 300 -> 390, through north, outside 20..340
    v = rig("dcu1", settings={"az_offset_deg": 180}, emulator={"start_az_deg": 120})
    cfg = v.cfg.motion
    v.run_for(cfg.az_span_deg / cfg.nominal_speed_deg_s + cfg.brake_delay_s + 1)
    assert v.status.available and v.status.raw_bearing_deg is None
    t = v.now
    with pytest.raises(Refused) as refused:  # the group's part, judged as the Rotator does
        v.aim(Target(30.0, within_deg=(20.0, 340.0)))
    assert refused.value.code is RefusalCode.LIMITS
    v.run_for(60)
    assert [f.data for f in v.frames(since=t)] == []  # nothing sent to the controller
    assert v.truth().az_deg == 120  # the antenna never swept through north
