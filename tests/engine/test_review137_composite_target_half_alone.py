"""Review 137 (session.py rule 13, runtime/composite.py rules 2 and 4), found while reviewing
293e4123 on an az/el rotator, older than 78f3d4fb. A target (both axes) sent in time under a
hold, then a late satellite look-up whose two answers straddle the marker: the box answered
under the hold begins tracking (feature_commands.py ``track``: its half of the target cleared),
which the marker then ends as late; the box answered after the marker ends the look-up as late
(``_waited``) and keeps its half of the target, which goes out. So one axis turns alone to its
half of the target (here the elevation, to 30, the azimuth left at 0) and nothing says the
other half was dropped. Answered in both boxes before the marker, neither axis turns; after it
in both, both go to the target.

Sequence: a Rotor-EZ azimuth box and a GS-232B elevation box; a STOP holds the rotator for its
marker; a target 120/30 (unstamped) under the hold; at 4.9 s a remote's ``track ISS (ZARYA)``
stamped to expire at 5 s, the azimuth box's sky answer 0.05 s after its question, the elevation
box's 0.4 s after; the marker back at 5.1 s."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.core.model import Source, Stop, Target
from bridge.session.tracking import Track
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.lookups import az_el_at_rest


@pytest.mark.xfail(
    strict=True,
    reason="review-137 5: on an az/el rotator, a late look-up answered in one box before the "
    "marker and in the other after it sends one half of a target alone",
)
def test_a_late_look_up_straddling_the_marker_sends_no_half_of_a_target_alone(
    tmp_path: Path,
) -> None:
    with az_el_at_rest(tmp_path) as (v, path):
        v.az.sky_delay_s, v.el.sky_delay_s = 0.05, 0.4  # each box's answer in its turn
        t = v.now
        v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
        v._take()
        v.aim(Target(120.0, 30.0))  # in time, under the hold
        v._take()
        v.run_for(4.9)
        lookup = LookupQuestion(TleCatalog(path), "ISS (ZARYA)")
        v.mailbox.put_track(
            Track(None, Source.MQTT, lookup, "track ISS (ZARYA)", not_after_s=t + 5.0)
        )
        v._take()  # taken in time, 0.1 s before its expiry
        v.run_for(t + 5.1 - v.now)
        assert v.az.frames("move", since=t) == [] and v.el.frames("move", since=t) == []
        v.mailbox.put_release(1)  # the marker back: past the look-up's expiry
        v._take()
        v.run_for(40)
        said = [e.message for box in v.boxes.values() for e in box.errors(since=t)]
        az_turned = v.az.frames("move", since=t) != []
        el_turned = v.el.frames("move", since=t) != []
        where = (v.az.truth().az_deg, v.el.truth().el_deg)
        assert az_turned == el_turned, (where, said)  # no axis turns alone
