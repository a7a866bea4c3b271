"""Attack 30: a Prosistel D turning a composite's elevation that reads a degree past its end is
offline for good, as review 49's RT-21 was before its fix.

axes.py rule 2 reads a one-axis elevation box's bearing up to EL_READ_SLACK_DEG past an end as
that end ("a pot a degree or two off with the weather, a coast past the end"), for every box
of ONE_AXIS_ELEVATION, ``prosistel-el`` and ``prosistel-el-a`` among them (their scale 0..90).
But the Prosistel codec judges the value first (prosistel.py rules 1 and 2: past the unit's
top, 90, SPOILED) and the one-axis wrapper never sees it: a D at its top end reading ``091``
gives no reading at all. The elevation box goes offline ("answers only garbled replies ...: a
noisy line?"), the rotator with it, and a target of 45 never turns it down: nothing the bridge
can do brings it back, the operator has to go to the box. The RT-21 in the same place reads
181 as 180 and is turned back (test_review49_one_axis_elevation_a_degree_past_its_end.py).

In virtual time, an emulated Prosistel D azimuth box and a D elevation box whose answers, from
the moment it rests at 90, say 91 (the line rewrites ``090`` as ``091``: a pot a degree off).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import Target
from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite

TOP_DEG = 90.0
DOWN_DEG = 45.0


def read_past_the_end(unit: bytes) -> Callable[[bytes, float], bytes]:
    """The box's answers as a pot a degree past its top says them: ``090`` read as ``091``
    (each line handed on whole at its CR)."""
    line = bytearray()

    def rewrite(data: bytes, now: float) -> bytes:
        line.extend(data)
        out = b""
        while b"\r" in line:
            end = line.index(b"\r") + 1
            whole = bytes(line[:end])
            del line[:end]
            out += whole.replace(b"\x02" + unit + b",?,090,", b"\x02" + unit + b",?,091,")
        return out

    return rewrite


@pytest.mark.parametrize(("model", "unit"), [("prosistel-el", b"E"), ("prosistel-el-a", b"A")])
def test_a_prosistel_elevation_box_a_degree_past_its_end_is_still_turned_back(
    model: str, unit: bytes
) -> None:
    emulators = {Axis.ELEVATION: {"start_el_deg": 80.0}}
    with VirtualComposite("prosistel", model, emulators=emulators) as v:
        v.run_for(10)
        v.aim(Target(0.0, TOP_DEG))
        v.run_until(lambda c: c.status.elevation_deg == TOP_DEG, 30, "up at its top end")
        v.run_for(5)  # at rest there
        v.el.to_host = read_past_the_end(unit)  # the pot a degree past the end
        v.run_for(20)
        v.aim(Target(0.0, DOWN_DEG))
        v.run_for(60)
        told = [e.message for e in v.el.errors()]
        assert v.el.truth().el_deg == pytest.approx(DOWN_DEG, abs=1.0), told
        assert v.status.available and v.status.elevation_deg == pytest.approx(DOWN_DEG, abs=1.0)
