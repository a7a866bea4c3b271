"""Review 103: a true first reading asked long after three garbled ones confirms the last garble,
which is taken for the bearing, and a nudge from it turns the rotor the wrong way.

controller.py rule 9 (``_doubts_first``) believes a connection's first reading when a later one
agrees within ``doubt_deg`` plus what the rotor can turn between the two at its top speed
(three times nominal), and takes the first of the two. After three first readings in a row
that disagree, the fourth is asked an idle poll later (on the SPID Rot2Prog 8.4 s after the
third answer: test_review103_first_readings_asked_at_the_idle_rate), so the allowance grows to
5 + 3 x 8.4 = 30 degrees: the true 150 "agrees" with a garbled 125 and 125 is taken. The
rotator comes online shown at 125 with the rotor at 150, then "moving" back to 150 with nothing
turning; a nudge of +10 made in that window is judged from 125 and turns the rotor down from 150
to 135, the wrong way. (The later of the two, not the first, or the allowance of the time the
question was meant to take, would not.)

In virtual time: the emulated Rot2Prog at rest at 150; its first three position frames reach
the host 40 on, 40 back and 25 back; the rest as sent.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import pytest

from bridge.core.model import Source
from tests.engine.garblers import frames_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
OFFSETS = [40.0, -40.0, -25.0]  # 190, 110, 125: no two agree, no three make a turn
NUDGE_DEG = 10.0
WATCH_S = 60.0  # a nudge's turn of 10 or 15 degrees at 1 deg/s, with room (virtual time)


def test_a_nudge_after_three_garbled_first_answers_turns_the_rotor_by_the_nudge(
    rig: Rig,
) -> None:
    v = rig("rot2prog", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = frames_off(OFFSETS)
    v.link_up()
    v.run_until(lambda h: h.status.available, 20, "the controller answers")
    shown = v.status.bearing_deg
    v.aim(replace(v.cfg.aim.nudge(v.status, NUDGE_DEG, None), source=Source.MQTT))
    lowest = REST_DEG
    t = v.now
    while v.now < t + WATCH_S:
        v.run_for(1.0)  # (a step of virtual time: not a deadline)
        lowest = min(lowest, v.truth().az_deg)
    assert lowest >= REST_DEG - 1.0, (
        f"a nudge of +{NUDGE_DEG:g} at {REST_DEG:g} (shown {shown}) turned the rotor down to "
        f"{lowest:g}"
    )
    assert v.truth().az_deg == pytest.approx(REST_DEG + NUDGE_DEG, abs=1.0)
