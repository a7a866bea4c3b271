"""Attack 30: an RC2800 whose pot reads a little past north, either end, is offline for good.

The RC2800's azimuth is a potentiometer read in tenths, and its spec allows a still rotor's
readings to wander ``noise_deg`` = 0.5. Its scale is 0..360 with both ends at north (a target
of 0 or 360 goes to that end). rc2800.py rule 3 spoils any azimuth outside 0..360, with no
slack: a rotor parked at either end whose pot says ``A P=  -0.2`` or ``A P= 360.2`` gives no
reading at all. The rotator goes offline ("answers only garbled replies ...: a noisy line?"),
the next target never turns it, and the operator has to go to the box. Review 39 gave an
Easycomm box half a degree either side of 0 and 360 for just this (a SatNOGS at rest at north
saying ``AZ-0.1``; Hamlib reads it); the RC2800 got none.

In virtual time: the emulated box turned to the end; from then on the line says its answers
as the pot a fifth of a degree past it.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.test_attack30_gs232_450_a_degree_past_its_end import read_past_the_end
from tests.engine.virtual import VirtualRotator


@pytest.mark.parametrize(
    ("start", "end", "said", "read", "back"),
    [
        (30.0, 0.0, b"A P=   0.0", b"A P=  -0.2", 100.0),
        (330.0, 360.0, b"A P= 360.0", b"A P= 360.2", 300.0),
    ],
)
def test_an_rc2800_a_fifth_of_a_degree_past_north_is_still_turned(
    rig: Callable[..., VirtualRotator],
    start: float,
    end: float,
    said: bytes,
    read: bytes,
    back: float,
) -> None:
    v = rig("rc2800-az", emulator={"start_az_deg": start})
    v.run_for(5)
    v.target(end)
    v.run_until(lambda h: h.truth().az_deg == end and not h.truth().is_moving, 30, "at north")
    v.run_for(5)  # at rest there
    v.to_host = read_past_the_end(said, read)  # the pot a fifth of a degree past the end
    v.run_for(20)
    v.target(back)
    v.run_for(60)
    told = [e.message for e in v.errors()]
    assert v.truth().az_deg == back, told
    assert v.status.available, told
