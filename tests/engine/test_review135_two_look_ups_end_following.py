"""Review 135 on 78f3d4fb (session.py rule 13): a look-up under a hold whose answer begins
nothing leaves what waited before it waiting as it was (review 37's fix). With two look-ups
before the first's answer, what waited before the second is the first merged with following
begun in time: the first's answer is stale (the second replaced it; tracking.py rule 8), the
second fails, and ``sky_answer`` puts the first's late expiry back. The marker, past it, ends
following that no start under the hold ended (review 37 again, by a second look-up).

Sequence: a STOP holds the rotator for its marker; WSJT-X following started in time under the
hold (unstamped); a remote's ``track nosuch`` (stamped, 5 s expiry), then, before its answer,
an unstamped ``track nosuch2``; both names are unknown ("no satellite"); the marker back 8 s
later. The parent (78f3d4fb^) has it too."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.sky.catalog import TleCatalog
from tests.engine.lookups import following_under_a_hold, look_up
from tests.engine.test_session_last_word import bearings, iss_tle, starts_rig
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.xfail(
    strict=True,
    reason=(
        "review-135 1: a second look-up before a late one's answer puts the late one's expiry "
        "back when it fails; following begun in time ends at the marker"
    ),
)
def test_two_failed_look_ups_under_a_hold_leave_following_begun_before_them_alone(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    v = starts_rig(rig, monkeypatch)
    t = v.now
    catalog = TleCatalog(iss_tle(v, tmp_path))
    following_under_a_hold(v)
    look_up(v, catalog, "nosuch", v.now + 5.0)  # late: the marker comes 8 s later
    look_up(v, catalog, "nosuch2", None)  # before the first's answer, unstamped
    v.run_for(8.0)
    assert v.status.following is not None  # (both failed: nothing changed)
    v.mailbox.put_release(1)  # the marker back, past the first look-up's expiry
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert v.status.following is not None, said
    assert bearings(v, since=t) != [], said  # the rotor turns to the QSO partner
