"""Review 116: a Rot2Prog whose line goes bad at rest is stopped once at the moving rate, then
polled at its 9.3 s idle rate: a hand turn after that first unwatched stop runs unstopped for
eight idle polls, about 50 s, past ``az_min_deg``.

controller.py rule 9 (review 103's follow-up, f23b2118): readings at rest that go on disagreeing
get the unwatched stop at each FIRST_UNWATCHED_READINGS (8) of them, "asked at the moving rate
until the first unwatched stop, then at the usual polls". The promise is the team's decision:
"the limits hold over a rotor the bridge cannot watch", and "each as many more while they go on
(a hand at the panel after the first such stop)". A Rot2Prog's idle poll is 9.3 s: eight of
them are up to 74 s. Review 111 found the same for a connection's first readings
(test_review111_rot2prog_unwatched_restop_at_the_idle_rate, fixed: those stay at the moving
rate); at rest the same line is polled at the idle rate after the first stop, and a hand at the
panel turning the rotor at its nominal 1 deg/s from 150 towards ``az_min_deg`` 120 is first
stopped again 49 s in, at about 101: 19 degrees past the limit.

In virtual time: the emulated Rot2Prog at rest at 150 (``az_min_deg`` 120), confirmed on a
clean line; then every position frame's azimuth reaches the host off by +60 or -60 in turn (a
line gone bad, never back where it stood); the first unwatched stop goes out; three seconds on,
a hand turns the rotor down to 5 at its speed.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import every_frame_off, limited, lowest_az
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 120.0
OFFSETS = [60.0, -60.0]
CONFIRMED_S = 15.0  # the start's readings on a clean line (virtual time, not a deadline)
FIRST_STOP_S = 60.0  # eight readings at the moving rate, with room (virtual time)
AFTER_S = 3.0  # the hand comes after the first unwatched stop (virtual time)
WATCH_S = 150.0  # 145 degrees at 1 deg/s, with room (virtual time)


def test_a_hand_turn_after_the_first_unwatched_stop_at_rest_is_stopped_before_the_limit(
    rig: Rig,
) -> None:
    v = limited(rig, "rot2prog", REST_DEG, AZ_MIN_DEG)
    v.link_up()
    v.run_for(CONFIRMED_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG  # (confirmed, clean line)
    v.to_host = every_frame_off(OFFSETS)
    t0 = v.now
    v.run_until(lambda h: bool(h.frames("stop", since=t0)), FIRST_STOP_S, "the unwatched stop")
    v.run_for(AFTER_S)
    assert v.truth().az_deg == REST_DEG  # (still: the first stop went to a rotor at rest)
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG)
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops written {stops} s into the turn"
    )
