"""Attack 12: a reading at rest whose elevation alone is a glitch (one flipped bit: 45 read as
145, a plausible value inside an RC2800's 0..180) is doubted and dropped as it should be
(session/controller.py rule 9), but the error it leaves on R/error measures the distance by
the azimuth alone: "a reading at rest of 150/145, 0° from where the rotor stands, was not said
again", where the elevation was 100 degrees off; the operator reads that nothing was wrong. In
virtual time on an emulated RC2800 az/el box."""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.virtual import VirtualRotator


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
    assert "150/145, 100° off in elevation from where the rotor stands" in said, said


def test_a_glitch_on_both_axes_at_rest_is_told_on_both(
    rig: Callable[..., VirtualRotator],
) -> None:
    """Rule 9's wording: a GS-232B reading at 150/45 glitched to 350/145 (a flipped bit in
    each axis's hundreds) is told off on both axes, each by its own distance (the azimuth's
    on the circle)."""
    v = rig("gs232b", emulator={"start_az_deg": 150.0, "start_el_deg": 45.0})
    v.run_until(lambda r: r.statuses and r.status.available, 30, "online")
    v.run_for(5)
    t = v.now
    glitched = v.read_once_as(b"A", b"AZ=350  EL=145\r\n")  # the next reply
    v.run_for(20)
    assert b"".join(glitched).startswith(b"AZ=150"), glitched
    assert {(s.bearing_deg, s.elevation_deg) for s in v.published(since=t)} <= {(150.0, 45.0)}
    [said] = [e.message for e in v.errors(since=t)]
    assert "350/145, 160° off in azimuth and 100° off in elevation from where" in said, said
