"""Review 142: under the lock, a start whose first readings never agree fights a hand at the
panel only with the unwatched stop, which 1b8194c1 spaces 7 s apart: a locked rotor is turned 36
degrees, where 1b8194c1^ held it within 4 and the same line at rest holds it within 6.

stops.py rule 7: while the lock holds, a reading at rest the doubt does not take is a sign the
rotor may be turning, and the lock's stop goes again (controller.py rule 9, ``Stops.lock_sign``).
A connection's first readings are no such sign (``_doubts_first``): what fights a hand there is
the unwatched stop at each FIRST_UNWATCHED_READINGS (8) of them. 1b8194c1 asks those readings
once a second after the first unwatched stop (UNWATCHED_POLL_S), the moving rate before: the
stops go 7 s apart instead of 1.6 s, and a hand at the panel of a locked Easycomm II at 6 deg/s
runs from 150 to 114 before the next. At rest, a locked rotor on the same line is stopped again
at every reading (about 6 degrees).

In virtual time: the emulated Easycomm II at rest at 150, the lock on from the start; every
answer's azimuth off by 0, +60 or -60 degrees in turn (review 100's line); the first unwatched
stop goes out; a second on, a hand turns the rotor down to 5 at its speed.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import every_answer_off, lowest_az
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
OFFSETS = [0.0, 60.0, -60.0]
LOCK_STOP_S = 0.5  # past the lock's own stop at the connect (virtual time, not a deadline)
FIRST_STOP_S = 60.0  # eight readings at the moving rate, with room (virtual time)
AFTER_S = 1.0  # the hand comes a second after the first unwatched stop (virtual time)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)
HELD_DEG = 10.0  # what a locked rotor may be turned before a stop: at rest, about 6


def test_a_locked_rotor_whose_first_readings_never_agree_is_held_against_a_hand(
    rig: Rig,
) -> None:
    v = rig("easycomm2", emulator={"start_az_deg": REST_DEG}, connect=False, locked=True)
    v.to_host = every_answer_off(OFFSETS)
    v.link_up()
    v.run_for(LOCK_STOP_S)
    t0 = v.now
    v.run_until(lambda h: bool(h.frames("stop", since=t0)), FIRST_STOP_S, "the unwatched stop")
    v.run_for(AFTER_S)
    assert v.truth().az_deg == REST_DEG and not v.status.available  # (still unconfirmed)
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel, against the lock)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG)
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    assert lowest >= REST_DEG - HELD_DEG, (
        f"a locked rotor turned by hand from {REST_DEG:g} down to {lowest:g}; stops written "
        f"{stops} s into the turn"
    )
