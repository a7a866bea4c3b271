"""Review 45 of 8d30f1d5 (pointing.py rule 2, ``_end_free``): a target sent to an end of the
travel it does not name has that end picked again from where the rotor is when it is sent,
but not a group member's bearing that its group offset brings to north
(``Target.az_either_end``): "its bearing is judged by its arc and the nearer end, once". A
member with no limits of its own has no arc (``within_deg`` None), nor does one whose limits
are the whole circle (``[0, 360]``: every turn stays inside, rule 9), and its end is still
picked once, when the target is judged, from the status's reading. A SatEL answers nothing while it
slews and stops before it takes a new point: its status shows the slew's estimate (session/
slew.py rule 3). A SatEL in group ``stack`` with ``offsets = { lower = 180 }``, turning from
raw 350 to raw 10 (back through its south), is sent the group's 180 (its north) mid-slew
while the estimate still says about 199 and the rotor is at about 148: it is sent ``p360``
after the stop and turns some 212 degrees through its south to the far end, where the same
bearing sent to the rotator itself (review 44's fix) goes to 0, 148 degrees back. What a user
notices: one antenna of the stack swings the long way round while the other turns the short
way.
(Fixed: such a member's end is picked again when it is sent, pointing.py ``_end_free``.)"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import Target
from bridge.interfaces.mqtt.groups import Group, Member, fan_out
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.parametrize("limits", [None, (0.0, 360.0)], ids=["no-limits", "limits-0-360"])
def test_a_satel_members_north_mid_slew_turns_to_the_nearer_end(
    rig: Rig, limits: tuple[float, float] | None
) -> None:
    v = rig("satel", emulator={"start_az_deg": 350})
    v.run_until(lambda h: h.status.raw_bearing_deg is not None, 10, "a reading")
    v.aim(Target(10.0, 20.0))  # a slew back through its south
    v.run_until(
        lambda h: (h.status.raw_bearing_deg or 360.0) < 200.0, 120, "the estimate under 200"
    )
    at = v.truth().az_deg
    assert at < 180.0  # the rotor itself is already nearer raw 0 than raw 360
    stack = Group("stack", "Stack", (Member("upper"), Member("lower", 180.0, limits)))
    part = fan_out(stack, b"180", {"upper": True, "lower": True})[1].target
    assert part is not None and part.az_either_end and part.within_deg == limits
    v.aim(part)  # judged as the member's Rotator judges it: the group's 180 is its north
    high = at
    for _ in range(120):
        v.run_for(1.0)
        high = max(high, v.truth().az_deg)
    assert high <= at + 10.0, (
        f"the SatEL stopped near raw {at:.0f} and turned on to raw {high:.0f} for the group's "
        f"180 (points sent: {[s for s in v.sent() if s.startswith(b'p')]})"
    )
    assert v.truth().az_deg == pytest.approx(0.0, abs=5.0)
