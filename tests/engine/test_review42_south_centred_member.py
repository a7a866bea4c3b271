"""Review 42 of attack 10's group fix (groups.py rule 2, pointing.py rule 2): where a member's
bearing lands on north of its controller's scale, it names neither end of the travel, and a
GS-232 takes the end nearer the rotor. The fix marks a part only where the group's offset
brings it there (``Target.az_either_end`` for a member with an offset); a member mounted
south-centred (``az_offset_deg = 180``, pointing.py rule 1: its controller's 0 and 360 are
true south) with no group offset gets the group's 180 unmarked, and rule 2 sends it raw 0
("0, not 360, where the offset brings a bearing there") wherever the rotor is: at raw 355
(true 175) it is sent ``M000`` and turns 355 degrees back through true north for a bearing 5
degrees away, attack 10's turn by the rotator's offset instead of the group's. (So does the
rotator's own ``R/target`` 180: rule 2 as written; the group's part names no end at all.)
(Fixed by abfe1b13: a bearing the rotator's own offset brings to north names neither end.)"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.interfaces.mqtt.groups import Group, Member, fan_out
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_a_south_centred_members_north_of_scale_turns_a_gs232_the_short_way(rig: Rig) -> None:
    v = rig("gs232b-az", settings={"az_offset_deg": 180}, emulator={"start_az_deg": 355})
    v.run_until(lambda h: h.status.raw_bearing_deg is not None, 10, "a reading")
    assert v.status.bearing_deg == pytest.approx(175.0, abs=1.0)
    stack = Group("stack", "Stack", (Member("upper"), Member("lower")))
    part = fan_out(stack, b"180", {"upper": False, "lower": False})[1].target
    assert part is not None
    v.aim(part)  # judged as the member's Rotator judges it
    low = high = v.truth().az_deg
    for _ in range(60):
        v.run_for(1.0)
        low, high = min(low, v.truth().az_deg), max(high, v.truth().az_deg)
    assert high - low <= 10.0, (
        f"the member at raw 355 (true 175) turned through raw {low:g}..{high:g} for true 180 "
        f"(sent {[f.data for f in v.frames('move')]})"
    )
