"""Review 137 (runtime/composite.py rule 4: "no axis tracks or follows alone"; tracking.py rule
8), found while reviewing 293e4123 on an az/el rotator, older than it. Each box's session asks
the sky worker for a satellite's name on its own, and the two answers come one after the other.
A second ``track`` by name taken between them replaces the look-up only in the box still
waiting for its answer (its answer, to another question, is then dropped as stale), while the
box answered first already tracks the satellite; the second name unknown, nothing ends that
tracking: the azimuth box tracks ISS alone, turning with its pass, the elevation box tracks nothing
and never will, and the rotator's status says it tracks ISS. Rule 4 ends tracking in the other
box only when one box *ends* it; a box that never began it is not seen. Under a hold, 78f3d4fb^
hid it (the late second look-up's expiry ended the azimuth box's tracking at the marker); since
78f3d4fb it shows there too. Without a hold, every version has it.

Sequence: a Rotor-EZ azimuth box and a GS-232B elevation box; ``track ISS (ZARYA)`` by name, the
azimuth box's sky answer 0.05 s after its question, the elevation box's 0.4 s after; 0.2 s
later ``track nosuch`` (a name the file does not have)."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.core.model import Source
from bridge.session.tracking import Track
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.lookups import az_el_at_rest


@pytest.mark.xfail(
    strict=True,
    reason="review-137 4: on an az/el rotator, a look-up replaced between the two boxes' answers "
    "leaves the azimuth box tracking alone",
)
def test_a_look_up_replaced_between_the_two_boxes_answers_tracks_no_axis_alone(
    tmp_path: Path,
) -> None:
    with az_el_at_rest(tmp_path) as (v, path):
        v.az.sky_delay_s, v.el.sky_delay_s = 0.05, 0.4  # each box's answer in its turn
        t = v.now
        catalog = TleCatalog(path)
        iss = LookupQuestion(catalog, "ISS (ZARYA)")
        v.mailbox.put_track(Track(None, Source.MQTT, iss, "track ISS (ZARYA)"))
        v._take()
        v.run_for(0.2)  # the azimuth box's answer in, the elevation box's not yet
        nosuch = LookupQuestion(catalog, "nosuch")
        v.mailbox.put_track(Track(None, Source.MQTT, nosuch, "track nosuch"))
        v._take()
        v.run_for(60)
        tracked = [box.status.tracking is not None for box in v.boxes.values()]
        where = (v.az.truth().az_deg, v.el.truth().el_deg)
        assert tracked[0] == tracked[1], (tracked, where)  # no axis tracks alone
        az_turned = v.az.frames("move", since=t) != []
        el_turned = v.el.frames("move", since=t) != []
        assert not (az_turned and not el_turned and tracked[0]), (tracked, where)
