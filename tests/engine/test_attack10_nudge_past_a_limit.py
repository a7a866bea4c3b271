"""Attack 10 on the judge (pointing.py rule 6): a nudge that would go past a limit of a rotor
whose scale does not wrap. A 450-degree Yaesu (GS-232B az/el box, azimuth 0..450) with the
limits narrowed to 20..440 (``az_min_deg = 20``), at 30: a nudge of -15 names true 15, raw
15, below the limit; the judge takes the only raw value of that bearing inside the limits,
375, and the rotor turns 345 degrees clockwise for a nudge of 15 counterclockwise. Rule 6:
"a nudge past an end ... is refused, never taken the whole way round, as past a SPID's stop";
a nudge "turns the short way it names". At the mechanical end (0..450, no narrowed limit) the
same nudge is refused. So it goes on a SPID (MD-01, limits 10..530, at 15, nudge -10: raw 365)
and with an offset on such a scale (``az_offset_deg = 90``, the model's own limits: at raw 10
a nudge of -20 goes to raw 350)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.core.errors import Refused
from bridge.core.model import Nudge, Origin, Source
from tests.engine.test_halt_epoch import START_AZ, Bench

WHO = Origin(Source.MQTT, "DL1ABC")


@pytest.fixture
def yaesu(tmp_path: Path) -> Iterator[Bench]:
    made = Bench(tmp_path, "gs232b-450", az_min_deg=20, az_max_deg=440)
    yield made
    made.close()


def test_a_nudge_past_a_narrowed_limit_never_turns_the_rotor_the_other_way(yaesu: Bench) -> None:
    yaesu.v.run_for(2.0)
    assert yaesu.rot.status.bearing_deg == pytest.approx(START_AZ, abs=1.0)
    try:
        yaesu.rot.submit(Nudge(-15.0, None, source=Source.MQTT, origin=WHO), "nudge '-15'")
    except Refused:
        pass  # the right answer: 15 is past the limit 20 this way
    yaesu.v._take()
    highest = START_AZ
    for _ in range(60):
        yaesu.v.run_for(1.0)
        highest = max(highest, yaesu.v.truth().az_deg)
    assert highest <= START_AZ + 1.0, (
        f"a nudge of -15 at {START_AZ:g} turned the rotor clockwise up to raw {highest:g} "
        f"(sent {[f.data for f in yaesu.v.frames('move')]})"
    )
