"""Review 111: a Rot2Prog whose first readings disagreed long enough for the unwatched stop is
shown offline for some 15 s more once its line comes right.

controller.py rule 9: "a line that comes right confirms on two of them" (commit 1170107f), and
from the first unwatched stop on those readings are asked at the idle rate. A Rot2Prog's idle
poll is 9.3 s: the first two sound answers are two idle polls apart, and the rotator stays
offline, no bearing and no target taken, for 14.9 s after its line is sound again, where a
healthy start takes under a second, as did the same line before the commit (0.9 s at
ba284eb8: the readings were asked at the moving rate).

In virtual time: the emulated Rot2Prog at rest at 150; every position frame's azimuth off by
0, +60 or -60 degrees in turn (review 100's line) for a minute from the start, then as sent.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import every_frame_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
OFFSETS = [0.0, 60.0, -60.0]
GARBLED_S = 60.0  # a minute of disagreeing first readings: several unwatched stops (virtual)
SOUND_S = 3.0  # a healthy start's confirmation (0.94 s) with room: a few exchanges (virtual)


def test_a_rot2prog_line_that_comes_right_is_confirmed_within_a_few_exchanges(rig: Rig) -> None:
    v = rig("rot2prog", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = every_frame_off(OFFSETS)
    v.link_up()
    v.run_for(GARBLED_S)
    assert v.frames("stop") and not v.status.available  # (stopped, unconfirmed)
    v.to_host = None
    v.run_until(lambda h: h.status.available, SOUND_S, "confirmed on the sound line")
    assert v.status.bearing_deg == REST_DEG
