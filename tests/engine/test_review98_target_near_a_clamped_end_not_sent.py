"""Review 98: a reading past an end within the read slack is that end (base.py rule 10), and
the bridge then judges a target near that end from the end, not from where the box said it
is: a target within ``tolerance_deg`` of the clamped reading is taken as reached and never
sent, and the rotor stays up to the slack plus the tolerance away from it, shown "there".

The case the slack's rule names as its risk, a box set up otherwise than configured: a GS-232
at P45 (a 450-degree rotor, G-1000DXA) configured as the 360-degree ``gs232b-az``, left by hand
at 363 (true 3). gs232.py rule 2 reads ``AZ=363`` as 360 (true 0), nothing said (the MISFIT
words come only from 364 on). A target of 357 is 3 from that, within the default tolerance:
nothing goes on the wire but polls, and the rotor stays at 363, 6 degrees from the target,
while R/status shows 0 and no error. The box said 363: sent ``M357`` it would have turned there
(a box whose pot reads 363 at its 360 end would turn 3 degrees, harmless). The same judgement
holds on every end the slack now covers (a 450-degree model's 451..453, a Prosistel D's
361..363 or 091..093, a G-5500's elevation 181..183), where the emulators cannot stand past
their ends to show it. Older than review 98 on the 360-degree GS-232s (AZ_DRIFT_DEG); the rule
10 it writes makes it every model's.

In virtual time: the session configured as ``gs232b-az``, the line's box a ``gs232b-az-450``
emulator (P45) resting at 363.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge import emulators
from tests.engine.virtual import VirtualRotator

AT_DEG = 363.0  # the box at P45, 3 past the configured model's 360 (true 3)
TARGET_DEG = 357.0  # 3 short of the clamped reading: within the default tolerance of it
TOLERANCE_DEG = 3.0  # settings/rotator.py's default tolerance_deg


@pytest.mark.xfail(
    strict=True,
    reason="review 98: a GS-232 box read 3 past its end (363 as 360) is never sent a target of "
    "357: the rotor stays 6 degrees off it, shown at 0 with no error",
)
def test_a_target_near_an_end_the_reading_was_clamped_to_is_still_turned_to(
    rig: Callable[..., VirtualRotator],
) -> None:
    v = rig("gs232b-az")
    v.device = emulators.create("gs232b-az-450", now=v.now, start_az_deg=AT_DEG)
    v.run_for(10)
    assert v.status.available, [e.message for e in v.errors()]
    t = v.now
    v.target(TARGET_DEG)
    v.run_for(60)
    told = [e.message for e in v.errors()]
    sent = [w for w in v.sent(since=t) if w.startswith(b"M")]
    assert abs(v.truth().az_deg - TARGET_DEG) <= TOLERANCE_DEG, (v.truth().az_deg, sent, told)
