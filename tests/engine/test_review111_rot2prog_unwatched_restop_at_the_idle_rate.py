"""Review 111: a Rot2Prog whose first readings never agree is stopped again only about once a
minute after the first unwatched stop, and a hand turn in between runs past ``az_min_deg``.

controller.py rule 9 stops a rotor whose connection's first readings confirmed none at each
FIRST_UNWATCHED_READINGS (8) of them, "a hand at the panel after the first such stop" (review
103). Commit 1170107f asks those readings at the idle rate from the first such stop on. A
Rot2Prog's idle poll is 9.3 s (600 baud): eight of them are up to 74 s, where before the commit
they came at the moving rate (a stop within a few seconds; this test passes at ba284eb8).
Review 107's guard, an Easycomm at an idle poll of 1 s, passes; a Rot2Prog at its nominal
1 deg/s, 30 degrees from its ``az_min_deg``, turned by a hand after the first stop, is first
stopped again 44 s into the turn, at 106: 14 degrees past the limit.

In virtual time: the emulated Rot2Prog at rest at 150 (``az_min_deg`` 120); every position
frame's azimuth off by 0, +60 or -60 degrees in turn (review 100's line) from the start; three
minutes on, a hand turns the rotor down to 5 at its speed.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import every_frame_off, limited, lowest_az
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 120.0
OFFSETS = [0.0, 60.0, -60.0]
GARBLED_S = 180.0  # three minutes of disagreeing first readings (virtual time)
WATCH_S = 150.0  # 145 degrees at 1 deg/s, with room (virtual time)
STEP_S = 0.1  # a step of virtual time to see the lowest bearing: not a deadline


def test_a_hand_turn_on_a_garbling_rot2prog_start_is_stopped_before_the_limit(rig: Rig) -> None:
    v = limited(rig, "rot2prog", REST_DEG, AZ_MIN_DEG)
    v.to_host = every_frame_off(OFFSETS)
    v.link_up()
    v.run_for(GARBLED_S)
    assert v.truth().az_deg == REST_DEG and not v.status.available  # (still unconfirmed)
    assert v.frames("stop")  # (the first unwatched stop was made)
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG, STEP_S)
    stops = [round(f.time_s - t, 2) for f in v.frames("stop", since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops written {stops} s into the turn"
    )
