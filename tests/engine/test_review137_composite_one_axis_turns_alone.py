"""Review 137 on 78f3d4fb and 293e4123 (session.py rule 13, runtime/composite.py rule 4): on an
az/el rotator of two boxes each session asks the sky worker for a look-up of its own, and the
two answers come one after the other. Since 78f3d4fb a box whose answer (no such satellite)
comes under the hold puts back what waited before it (tracking the sun, asked for in time), while
a box whose answer comes after the marker still judges the two as one by the late look-up's
expiry and ends its tracking there (review 137 finding 1). So at the marker the first box sends
its axis to the sun, the second ends tracking, and rule 4 then ends it in the first: the rotator
says it tracks nothing, and one axis has turned alone (here the azimuth, 60 degrees, the
elevation left at 0; the other way round the elevation rises alone). The parent (78f3d4fb^)
ended tracking in both boxes and turned neither axis.

Sequence: a Rotor-EZ azimuth box and a GS-232B elevation box; a STOP holds the rotator for its
marker; ``track sun`` (unstamped, in time) under the hold; at 4.9 s a remote's ``track nosuch``
stamped to expire at 5 s, the azimuth box's sky answer 0.05 s after its question, the elevation
box's 0.4 s after; the marker back at 5.1 s."""

from __future__ import annotations

from pathlib import Path

from bridge.core.model import Source, Stop
from bridge.session.tracking import Track
from bridge.sky import Body
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.lookups import az_el_at_rest


def test_a_late_look_up_answered_in_one_box_before_the_marker_turns_no_axis_alone(
    tmp_path: Path,
) -> None:
    with az_el_at_rest(tmp_path) as (v, path):
        v.az.sky_delay_s, v.el.sky_delay_s = 0.05, 0.4  # each box's answer in its turn
        t = v.now
        v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
        v.mailbox.put_track(Track(Body.sun(), described="track sun"))  # in time, under the hold
        v._take()
        v.run_for(4.9)
        lookup = LookupQuestion(TleCatalog(path), "nosuch")  # a name the file does not have
        v.mailbox.put_track(Track(None, Source.MQTT, lookup, "track nosuch", not_after_s=t + 5.0))
        v._take()  # taken in time, 0.1 s before its expiry
        v.run_for(t + 5.1 - v.now)
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
