"""Review 44 of abfe1b13 (pointing.py rule 2: a bearing the rotator's offset brings to north
names neither end, and goes to the end nearer the rotor's reading). The end is picked once,
when the target is judged, from the status's reading, and kept: on a scale that wraps the
target carries no free side (``Target.true_az_deg`` None) and the engine sends the raw value
as judged (session/targets.py ``resolve``). A SatEL answers nothing while it slews and stops
before it takes a new point (``STOP_AND_WAIT``): its status shows the slew's estimate
(session/slew.py rule 3), and the target goes out only after the stop. A south-centred SatEL
(``az_offset_deg = 180``) turning from raw 350 to raw 10 (true 190), asked mid-slew for true
180 while the estimate still said raw 199 and the rotor was at raw 148, was sent ``p360``
after the stop and turned 212 degrees clockwise through its south to the end it stood 148
degrees from; before abfe1b13 it went to 0. What a user notices: the antenna swings the long
way round for a bearing it was heading towards. (The end is not re-picked from where the rotor
is when the target is sent, as rule 2 picks a side on a scale that can pass 360.)
(Fixed: such a target's end is picked again when it is sent, pointing.py ``_end_free``.)"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import Target
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_a_satel_asked_for_its_north_mid_slew_turns_to_the_nearer_end(rig: Rig) -> None:
    v = rig("satel", settings={"az_offset_deg": 180}, emulator={"start_az_deg": 350})
    v.run_until(lambda h: h.status.raw_bearing_deg is not None, 10, "a reading")
    v.aim(Target(190.0, 20.0))  # raw 10: a slew back through its south
    v.run_until(
        lambda h: (h.status.raw_bearing_deg or 360.0) < 200.0, 120, "the estimate under 200"
    )
    at = v.truth().az_deg
    assert at < 180.0  # the rotor itself is already nearer raw 0 than raw 360
    v.aim(Target(180.0, 20.0))  # true 180: the controller's north, named as neither end
    high = at
    for _ in range(120):
        v.run_for(1.0)
        high = max(high, v.truth().az_deg)
    assert high <= at + 10.0, (
        f"the SatEL stopped near raw {at:.0f} and turned on to raw {high:.0f} for true 180 "
        f"(points sent: {[s for s in v.sent() if s.startswith(b'p')]})"
    )
    assert v.truth().az_deg == pytest.approx(0.0, abs=5.0)
