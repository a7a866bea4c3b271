"""Review 137 on 293e4123 (session.py rule 13): a late look-up under a hold whose answer begins
nothing leaves what waited before it as it was (review 37, review 135), but only when that
answer comes before the hold's end. When the marker comes first (the sky worker a fraction of a
second behind: a look-up taken just before its expiry, the marker just after it), ``_waited``
still judges the look-up and the start before it as one, by the look-up's sooner expiry, and
``_began`` sees the look-up under way: it ends everything (``_end(EXPIRED)``), following begun
in time under the same hold included, said as the look-up's end ("tracking ended: its expiry
passed", track nosuch). The look-up's answer, had it come 0.4 s sooner, would have left following
alone; a late look-up with no hold would have been refused alone. The parents (78f3d4fb^ and
78f3d4fb) have it too.

Sequence: a STOP holds the rotator for its marker; WSJT-X following started in time under the
hold (unstamped); 4.8 s later a remote's ``track nosuch`` stamped to expire at 5 s is taken (in
time), the sky worker answering 0.5 s after a question; the marker back at 5.1 s."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.core.model import Source
from bridge.session.tracking import Track
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.lookups import following_under_a_hold
from tests.engine.test_session_last_word import bearings, iss_tle, starts_rig
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.xfail(
    strict=True,
    reason="review-137 1: a late look-up still unanswered when the marker comes ends following "
    "begun in time under the same hold",
)
def test_a_late_look_up_unanswered_at_the_marker_leaves_following_begun_before_it_alone(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    v = starts_rig(rig, monkeypatch)
    t = v.now
    catalog = TleCatalog(iss_tle(v, tmp_path))
    v.sky_delay_s = 0.5  # the sky worker a little behind (busy with another rotator's pass)
    following_under_a_hold(v)
    v.run_for(4.8)
    lookup = LookupQuestion(catalog, "nosuch")  # a name the file does not have
    v.mailbox.put_track(
        Track(None, Source.MQTT, lookup, described="track nosuch", not_after_s=t + 5.0)
    )
    v._take()  # taken in time, 0.2 s before its expiry
    v.run_for(0.3)
    assert bearings(v, since=t) == [] and v.status.following is not None  # (held)
    v.mailbox.put_release(1)  # the marker back, just past the look-up's expiry
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert v.status.following is not None, said
    assert bearings(v, since=t) != [], said  # the rotor turns to the QSO partner
