"""Attack 12: an RT-21 turning a composite rotator's elevation reads its one bearing as the
elevation (protocols/axes.py rule 2: "0..180 of its range"), but nothing holds a reading to that
range: a box that says ``300.0;`` (a pot past its end, a box calibrated for an azimuth rotor)
is published as elevation 300 on R/status, with el_max_deg 90 and the axis's own top 180,
and nothing on R/error. The next target's elevation of 30 then goes out as ``AP1030.0`` and
the box turns its rotor 270 degrees down through its whole travel. A reading past the axis's
scale is no elevation: said, and never shown nor counted from (as a Prosistel's position
past its unit's range, prosistel.py rule 1). In virtual time, two emulated RT-21 boxes."""

from __future__ import annotations

import pytest

from bridge.core.model import Target
from bridge.protocols import REGISTRY
from bridge.protocols.axes import ONE_AXIS_EL_MAX_DEG, Axis, axis_spec
from bridge.protocols.base import JunkReason, JunkReply, PositionReply
from tests.engine.virtual_composite import VirtualComposite


def test_an_elevation_box_reading_past_the_axis_scale_is_said_and_never_shown() -> None:
    with VirtualComposite(
        "rt21",
        "rt21",
        settings={"el_max_deg": 90},
        emulators={Axis.ELEVATION: {"start_az_deg": 300.0}},
    ) as v:
        v.run_for(10)
        shown = {s.elevation_deg for _, s in v.statuses if s.elevation_deg is not None}
        assert all(0.0 <= el <= ONE_AXIS_EL_MAX_DEG for el in shown), shown
        assert v.el.errors(), "the elevation box's reading of 300 was taken without a word"
        words = [r.message for r in v.el.errors()]
        assert any("reads 300" in w and "0..180" in w for w in words), words
        t = v.now
        v.aim(Target(10.0, 30.0))
        v.run_for(60)
        turns = [w for w in v.el.sent(since=t) if w.startswith(b"AP1")]
        assert turns == [] and v.el.truth().az_deg == 300.0, turns


@pytest.mark.parametrize(
    ("said", "reading"),
    [
        (b"45.0;", 45.0),
        (b"180.0;", 180.0),
        (b"180.4;", 180.0),
        (b"183.0;", 180.0),  # a pot a little past its end (review 49: 181 was offline for good)
        (b"183.5;", None),
        (b"0.0;", 0.0),
        (b"359.0;", 0.0),  # the RT-21's bearings wrap: a little below the horizon
        (b"357.0;", 0.0),
        (b"356.5;", None),
        (b"300.0;", None),
    ],
)
def test_an_elevation_boxs_bearing_is_read_in_the_axis_scale_and_a_little_past_its_ends(
    said: bytes, reading: float | None
) -> None:
    codec = axis_spec(REGISTRY["rt21"], Axis.ELEVATION).codec_factory()
    codec.encode_query()
    replies = codec.feed(said)
    assert [r.el_deg for r in replies if isinstance(r, PositionReply)] == (
        [] if reading is None else [reading]
    )
    misfits = [r for r in replies if isinstance(r, JunkReply) and r.reason is JunkReason.MISFIT]
    assert len(misfits) == (reading is None)


def test_a_target_waits_while_the_elevation_box_reads_past_the_axis_scale() -> None:
    """Online at 45, the box starts to read 300 (its pot gone past its end): a target's
    elevation given then is never sent to it while it reads so: the box would turn from a
    bearing nobody knows."""
    with VirtualComposite("rt21", "rt21", emulators={Axis.ELEVATION: {"start_az_deg": 45.0}}) as v:
        v.run_for(10)
        assert v.status.elevation_deg == 45.0 and v.status.available
        v.el.to_host = lambda data, now: b"300.0;" if data.strip(b" ;") else data
        v.run_for(3)
        t = v.now
        v.aim(Target(10.0, 30.0))
        v.run_for(30)
        turns = [w for w in v.el.sent(since=t) if w.startswith(b"AP1")]
        assert turns == [] and v.el.truth().az_deg == 45.0, turns
        assert any("reads 300" in r.message for r in v.el.errors()), v.el.errors()
        shown = {s.elevation_deg for _, s in v.statuses if s.elevation_deg is not None}
        assert shown <= {45.0}, shown
