"""Attack 12: a reading at rest whose elevation alone is a glitch (one flipped bit: 45 read as
145, a plausible value inside an RC2800's 0..180) is doubted and dropped as it should be
(session/controller.py rule 9), but the error it leaves on R/error measures the distance by
the azimuth alone: "a reading at rest of 150/145, 0° from where the rotor stands, was not said
again", where the elevation was 100 degrees off; the operator reads that nothing was wrong. In
virtual time on an emulated RC2800 az/el box."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.virtual import VirtualRotator


@pytest.mark.xfail(
    strict=True,
    reason="attack 12: an elevation glitch at rest (45 read as 145) is told on R/error as "
    "'0° from where the rotor stands'",
)
def test_an_elevation_glitch_at_rest_is_told_with_how_far_off_it_was(
    rig: Callable[..., VirtualRotator],
) -> None:
    v = rig("rc2800", emulator={"start_az_deg": 150.0, "start_el_deg": 45.0})
    v.run_until(lambda r: r.statuses and r.status.available, 30, "online")
    v.run_for(5)
    t = v.now
    glitched = v.glitch_once(b"E", b"E P=145.0 S=9 ST\r")  # before the next elevation line
    v.run_for(20)
    assert glitched
    assert {s.elevation_deg for s in v.published(since=t)} == {45.0}  # never shown: as it should
    [said] = [e.message for e in v.errors(since=t)]
    assert "150/145" in said
    assert ", 0° from where the rotor stands" not in said, said
