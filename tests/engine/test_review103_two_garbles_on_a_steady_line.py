"""Review 103: two garbled first answers that lie on one line with the true one are taken for a
turn, shown as the bearing, and a nudge from it turns the rotor the wrong way.

controller.py rule 9 (``_steady``, commit ee275169) takes three first readings in a row that
disagree but lie on one steady turn (each axis the same way, at FIRST_TURN_MAX_DEG_S = 60 deg/s
at most, the third within ``doubt_deg`` of the line) as a turn, the last of them where the
rotor is. On a SPID Rot2Prog (600 baud, an exchange every 0.47 s, its nominal 1 deg/s) a step of
10 degrees an exchange is 21 deg/s: well within that rate, and twice what the rotor can turn
(``doubt_deg`` plus its top speed between two answers is 6.4 degrees), so two such answers
never agree but three make a line. The rotor at rest at 150, its first answer true and the next
two garbled to 160 and 170 (the tens digit of the pulse count, ``1`` read ``2`` then ``3``): the
bridge shows the rotator online at 170 and idle, then "moving" for two seconds back to 150 with
nothing turning. A nudge of -10 made in that window (``R/nudge``, the console's arrows) is
judged from 170: the rotor turns up from 150 to 160, the wrong way.

In virtual time: the emulated Rot2Prog at rest at 150; its second and third position frames
reach the host 10 and 20 degrees on; the rest as sent.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import pytest

from bridge.core.model import MotionState, Source
from tests.engine.garblers import frames_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
OFFSETS = [0.0, 10.0, 20.0]  # the first frame true, the next two on one line with it
NUDGE_DEG = -10.0
WATCH_S = 60.0  # a nudge's turn of 10 degrees at 1 deg/s, with room (virtual time)


def started(rig: Rig) -> VirtualRotator:
    v = rig("rot2prog", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = frames_off(OFFSETS)
    v.link_up()
    v.run_until(lambda h: h.status.available, 5, "the controller answers")
    return v


def test_a_nudge_after_two_garbles_on_one_line_turns_the_rotor_by_the_nudge(rig: Rig) -> None:
    v = started(rig)
    shown = v.status.bearing_deg
    v.aim(replace(v.cfg.aim.nudge(v.status, NUDGE_DEG, None), source=Source.MQTT))
    highest = REST_DEG
    t = v.now
    while v.now < t + WATCH_S:
        v.run_for(1.0)  # (a step of virtual time: not a deadline)
        highest = max(highest, v.truth().az_deg)
    assert highest <= REST_DEG + 1.0, (
        f"a nudge of {NUDGE_DEG:g} at {REST_DEG:g} (shown {shown}) turned the rotor up to "
        f"{highest:g}"
    )
    assert v.truth().az_deg == pytest.approx(REST_DEG + NUDGE_DEG, abs=1.0)


def test_two_garbles_on_one_line_are_never_shown_nor_a_move(rig: Rig) -> None:
    v = started(rig)
    v.run_for(WATCH_S)
    assert not v.truth().is_moving and v.truth().az_deg == REST_DEG
    shown = {s.bearing_deg for s in v.published() if s.available} - {None}
    states = {s.state for s in v.published() if s.available}
    assert shown == {REST_DEG}, shown
    assert MotionState.MOVING not in states, states
