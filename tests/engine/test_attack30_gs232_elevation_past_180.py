"""Attack 30: a GS-232 whose elevation pot reads a degree past 180 is offline for good.

gs232.py rule 2 reads K3NG's elevation up to 3 degrees below the horizon as the horizon (a pot
a degree off: review 39), and an azimuth up to AZ_DRIFT_DEG past the top of a 360-degree scale
as the top; the other end of the elevation gets no such slack: ``EL=181`` (``+0181`` in the A
form) is "position out of range", SPOILED. A G-5500 flipped up to its 180 end whose pot reads a
degree past it gives no reading at all: the rotator goes offline ("answers only garbled
replies ...: a noisy line?"), a target of 90 never brings it down, and the operator has to go
to the controller (axes.py rule 2 reads a one-axis elevation box 3 degrees past 180 as 180 for
just this reason: review 49).

In virtual time: the emulated box turned up to elevation 180; from then on the line says its
answers a degree higher (``EL=180`` read as ``EL=181``, ``+0180`` as ``+0181``).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.test_attack30_gs232_450_a_degree_past_its_end import read_past_the_end
from tests.engine.virtual import VirtualRotator

AZ_DEG = 100.0
TOP_DEG = 180.0
DOWN_DEG = 90.0


@pytest.mark.parametrize(
    ("model", "said", "read"),
    [("gs232b", b"EL=180", b"EL=181"), ("gs232a", b"+0180\r", b"+0181\r")],
)
def test_a_gs232_elevation_a_degree_past_180_is_still_brought_down(
    rig: Callable[..., VirtualRotator], model: str, said: bytes, read: bytes
) -> None:
    v = rig(model, emulator={"start_az_deg": AZ_DEG, "start_el_deg": 170.0})
    v.run_for(5)
    v.target(AZ_DEG, TOP_DEG)
    v.run_until(lambda h: h.truth().el_deg == TOP_DEG and not h.truth().is_moving, 30, "up")
    v.run_for(5)  # at rest at its end
    v.to_host = read_past_the_end(said, read)  # the pot a degree past the end
    v.run_for(20)
    v.target(AZ_DEG, DOWN_DEG)
    v.run_for(60)
    told = [e.message for e in v.errors()]
    assert v.truth().el_deg == DOWN_DEG, told
    assert v.status.available, told
