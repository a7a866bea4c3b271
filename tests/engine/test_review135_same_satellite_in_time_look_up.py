"""Review 135 on 78f3d4fb (session.py rule 13), the mirror of finding 3: ``sky_answer`` reads
a look-up's answer that names the satellite already tracked as "began nothing" (the new
``Body`` equals the old one), though it ended that tracking and began it anew
(feature_commands.py ``track``). So a look-up sent again in time, after a late stamped one
began tracking under the same hold, is not judged alone (review 38: "once its answer begins
tracking under the hold, it is judged alone"): the late one's expiry, put back as what waited
before, ends at the marker the tracking the in-time one began ("tracking ended: its expiry
passed", named after the late command). With any other body the in-time start would be judged
alone and tracking would go on; so would a ``track sun`` sent again by body. The parent
(78f3d4fb^) has it too (it judged the two as one, by the sooner expiry).

Sequence: a STOP holds the rotator for its marker; ``track ISS (ZARYA)`` stamped with a 5 s
expiry under the hold, answered: tracking; ``track ISS (ZARYA)`` again, unstamped (in time),
answered: tracking begun anew; the marker back 8 s after the first."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.core.model import Source, Stop
from bridge.sky.catalog import TleCatalog
from tests.engine.lookups import look_up
from tests.engine.test_session_last_word import bearings, iss_tle, starts_rig
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.xfail(
    strict=True,
    reason=(
        "review-135 4: a look-up of the satellite tracked, sent again in time, is read as "
        "'began nothing'; the earlier late one's expiry ends its tracking at the marker"
    ),
)
def test_a_look_up_sent_again_in_time_under_the_hold_goes_on_tracking(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    v = starts_rig(rig, monkeypatch)
    t = v.now
    catalog = TleCatalog(iss_tle(v, tmp_path))
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
    v._take()
    look_up(v, catalog, "ISS (ZARYA)", t + 5.0)  # late: the marker comes 8 s later
    v.run_for(1.0)
    assert v.status.tracking is not None  # (its answer began tracking)
    look_up(v, catalog, "ISS (ZARYA)", None)  # sent again, in time
    v.run_for(7.0)
    assert bearings(v, since=t) == []  # (held)
    v.mailbox.put_release(1)  # the marker back, past the first look-up's expiry
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert v.status.tracking is not None, said
    assert bearings(v, since=t) != [], said  # the rotor turns to the pass
