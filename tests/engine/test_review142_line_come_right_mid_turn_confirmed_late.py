"""Review 142: a start's line that comes right while the rotor turns, after the first unwatched
stop, is confirmed seconds late: 1b8194c1 asks once a second, and two readings of a rotor at
6 deg/s a second apart never agree.

controller.py rule 9: a connection's first readings are believed when two agree within
``doubt_deg`` alone, or FIRST_TURN_READINGS (4) lie on one steady turn. Before 1b8194c1 they were
asked at the moving rate (0.2 s): two healthy readings of a turning rotor 1.2 degrees apart
agree at once (confirmed within 0.35 s of the line coming right, at any phase of the polls;
this test passes at 1b8194c1^). 1b8194c1 asks them once a second after the first unwatched
stop (UNWATCHED_POLL_S): two readings 6 degrees apart never agree, the turn needs four on its
line, and the rotator stays offline, no bearing shown, 3.5 s after the line came right.

In virtual time: the emulated Easycomm II at rest at 150; every answer's azimuth off by 0, +60 or
-60 degrees in turn (review 100's line) from the start; 24 s on, a hand at the panel turns it
down towards 5; half a second later the line comes right.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import every_answer_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
OFFSETS = [0.0, 60.0, -60.0]
GARBLED_S = 24.0  # past the first unwatched stops (virtual time, not a deadline)
TURNING_S = 0.5  # the hand's turn under way when the line comes right (virtual time)
CONFIRMED_S = 1.0  # how soon two healthy readings are believed: 1b8194c1^ within 0.35 s
WATCH_S = 30.0  # for the run to end where it never confirms (virtual time)


def test_a_line_that_comes_right_while_the_rotor_turns_is_confirmed_at_once(rig: Rig) -> None:
    v = rig("easycomm2", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = every_answer_off(OFFSETS)
    v.link_up()
    v.run_for(GARBLED_S)
    assert v.frames("stop") and not v.status.available  # (unwatched stops, unconfirmed)
    v.manual_rotate(5.0)  # (a hand at the panel)
    v.run_for(TURNING_S)
    assert v.truth().is_moving
    v.to_host = None  # (the line comes right)
    t = v.now
    v.run_until(lambda h: h.status.available, WATCH_S, "the first readings confirmed")
    assert v.now - t <= CONFIRMED_S, (
        f"offline for {v.now - t:.2f} s after the line came right, the rotor now at "
        f"{v.truth().az_deg:.0f}"
    )
