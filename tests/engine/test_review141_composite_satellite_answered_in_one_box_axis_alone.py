"""Review 141 on 08833d2b (session.py rule 13, runtime/composite.py rule 4): review 137's case 3
with a satellite the file has. On an az/el rotator of two boxes, ``track sun`` is taken in time
under a hold, then a late look-up of a satellite the TLE file has; one box's sky answer comes
under the hold, the other's after the marker. The box answered under the hold begins tracking
the satellite, which the marker ends as late; since 08833d2b the box still waiting drops the
look-up alone and goes on tracking the sun, asked for in time, and its step at the marker sends
its axis to the sun in the same serve, before rule 4 ends its tracking for the other box's end.
So one axis turns alone (the elevation to 40, the azimuth left at 0; the other way round the
azimuth to 59.5) while the rotator says it tracks nothing. The parents (08833d2b^ and
78f3d4fb^) ended tracking in both boxes at the marker and turned neither axis.

Sequence: a Rotor-EZ azimuth box and a GS-232B elevation box; a STOP holds the rotator for its
marker; ``track sun`` (unstamped, in time) under the hold; at 4.9 s a remote's ``track ISS
(ZARYA)`` by name stamped to expire at 5 s, one box's sky answer 0.05 s after its question, the
other's 0.4 s after; the marker back at 5.1 s."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.core.model import Source, Stop
from bridge.session.tracking import Track
from bridge.sky import Body
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.lookups import az_el_at_rest


@pytest.mark.parametrize(
    "az_delay_s, el_delay_s", [(0.05, 0.4), (0.4, 0.05)], ids=["az-first", "el-first"]
)
def test_a_late_satellite_answered_in_one_box_before_the_marker_turns_no_axis_alone(
    tmp_path: Path, az_delay_s: float, el_delay_s: float
) -> None:
    with az_el_at_rest(tmp_path) as (v, path):
        v.az.sky_delay_s, v.el.sky_delay_s = az_delay_s, el_delay_s  # the answers in turn
        t = v.now
        v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
        v.mailbox.put_track(Track(Body.sun(), described="track sun"))  # in time, under the hold
        v._take()
        v.run_for(4.9)
        lookup = LookupQuestion(TleCatalog(path), "ISS (ZARYA)")
        v.mailbox.put_track(
            Track(None, Source.MQTT, lookup, "track ISS (ZARYA)", not_after_s=t + 5.0)
        )
        v._take()  # taken in time, 0.1 s before its expiry
        v.run_for(t + 5.1 - v.now)
        tracked = [box.status.tracking is not None for box in v.boxes.values()]
        assert tracked == [True, True]  # (one box the satellite, the other the sun)
        assert v.az.frames("move", since=t) == [] and v.el.frames("move", since=t) == []
        v.mailbox.put_release(1)  # the marker back: past the look-up's expiry
        v._take()
        v.run_for(30)
        said = [e.message for box in v.boxes.values() for e in box.errors(since=t)]
        az_turned = v.az.frames("move", since=t) != []
        el_turned = v.el.frames("move", since=t) != []
        where = (v.az.truth().az_deg, v.el.truth().el_deg)
        assert az_turned == el_turned, (where, said)  # no axis turns alone
        assert (v.status.tracking is not None) == az_turned, (where, said)
