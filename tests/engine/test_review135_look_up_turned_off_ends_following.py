"""Review 135 on 78f3d4fb (session.py rule 13): a look-up under a hold is judged with what
waited before it, by the sooner expiry, until its answer; an answer that begins nothing puts
what waited before back (review 37's fix). A look-up that never answers, because ``track
OFF`` dropped it first (tracking.py ``end``: "its answer comes too late"), keeps its expiry
merged all the same: the marker, past it, ends following begun in time under the hold, which
neither the look-up nor the OFF ended (review 37 again, by a track OFF).

Sequence: a STOP holds the rotator for its marker; WSJT-X following started in time under the
hold (unstamped); a remote's ``track nosuch`` (stamped, 5 s expiry), then ``track OFF`` before
its answer; the marker back 8 s later. The parent (78f3d4fb^) has it too."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.core.model import Source
from bridge.session.tracking import Track
from bridge.sky.catalog import TleCatalog
from tests.engine.lookups import following_under_a_hold, look_up
from tests.engine.test_session_last_word import bearings, iss_tle, starts_rig
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.xfail(
    strict=True,
    reason=(
        "review-135 2: a late look-up dropped by track OFF before its answer keeps its expiry "
        "merged; following begun in time ends at the marker"
    ),
)
def test_a_late_look_up_turned_off_under_a_hold_leaves_following_begun_before_it_alone(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    v = starts_rig(rig, monkeypatch)
    t = v.now
    catalog = TleCatalog(iss_tle(v, tmp_path))
    following_under_a_hold(v)
    look_up(v, catalog, "nosuch", v.now + 5.0)  # late: the marker comes 8 s later
    v.mailbox.put_track(Track(None, Source.MQTT))  # track OFF, before the look-up's answer
    v._take()
    v.run_for(8.0)
    assert v.status.following is not None  # (tracking OFF ends no following)
    v.mailbox.put_release(1)  # the marker back, past the look-up's expiry
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert v.status.following is not None, said
    assert bearings(v, since=t) != [], said  # the rotor turns to the QSO partner
