"""Review 141 on 08833d2b (session.py rule 13, runtime/composite.py rule 4), older than it: review
137's finding 2 on an az/el rotator of two boxes. A late stamped ``track sun`` is taken under a
hold, then a satellite's look-up stamped well in time; one box's sky answer comes under the
hold, the other's after the marker. The box answered under the hold tracks the satellite, judged
alone (review 38), in time; the box still waiting judges the late ``track sun`` before it, whose
expiry ends its tracking and its look-up too (``_began``: the look-up counts as begun by it). At
the marker the first box's step sends its axis to where the pass rises, in the same serve,
before rule 4 ends its tracking for the other box's end: the azimuth turns alone (here from 0
towards 354, half a turn and more on an RT-21), the elevation left at 0, while the rotator says
it tracks nothing and the only word is the late sun's end. The parents (08833d2b^, 78f3d4fb^)
have it too.

Sequence: a Rotor-EZ azimuth box and a GS-232B elevation box; a STOP holds the rotator for its
marker; a remote's ``track sun`` stamped to expire at 5 s under the hold; at 4.9 s ``track ISS
(ZARYA)`` by name, stamped to expire at 30 s, the azimuth box's sky answer 0.05 s after its
question, the elevation box's 0.4 s after; the marker back at 5.1 s."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.core.model import Source, Stop
from bridge.session.tracking import Track
from bridge.sky import Body
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.lookups import az_el_at_rest


@pytest.mark.xfail(
    strict=True,
    reason="review-141 2: on an az/el rotator, a satellite asked for in time after a late start, "
    "answered in the azimuth box before the marker and not in the other, turns the azimuth alone",
)
def test_a_satellite_asked_for_in_time_answered_in_one_box_turns_no_axis_alone(
    tmp_path: Path,
) -> None:
    with az_el_at_rest(tmp_path) as (v, path):
        v.az.sky_delay_s, v.el.sky_delay_s = 0.05, 0.4  # each box's answer in its turn
        t = v.now
        v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
        v.mailbox.put_track(Track(Body.sun(), described="track sun", not_after_s=t + 5.0))
        v._take()
        v.run_for(4.9)
        lookup = LookupQuestion(TleCatalog(path), "ISS (ZARYA)")
        v.mailbox.put_track(
            Track(None, Source.MQTT, lookup, "track ISS (ZARYA)", not_after_s=t + 30.0)
        )
        v._take()
        v.run_for(t + 5.1 - v.now)
        assert v.az.frames("move", since=t) == [] and v.el.frames("move", since=t) == []
        v.mailbox.put_release(1)  # the marker back: past the sun's expiry, not the look-up's
        v._take()
        v.run_for(30)
        said = [e.message for box in v.boxes.values() for e in box.errors(since=t)]
        az_turned = v.az.frames("move", since=t) != []
        el_turned = v.el.frames("move", since=t) != []
        where = (v.az.truth().az_deg, v.el.truth().el_deg)
        assert az_turned == el_turned, (where, said)  # no axis turns alone
        assert (v.status.tracking is not None) == az_turned, (where, said)
