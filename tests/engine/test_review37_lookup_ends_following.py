"""Review 37 on c222c9df (session.py rule 13): a stamped start taken under a hold that ends past
its expiry ends what *it* began. A track start by a satellite's name (a look-up) begins
nothing but the look-up at take time (tracking.py rule 8: whatever is tracked or followed
goes on until the answer, and an unknown name changes nothing). Yet when the hold ends past
its expiry the session ends following too, begun in time under the same hold by another
start the look-up never ended: ``_waited`` asks whether anything at all is tracked or
followed, not whether the waiting start began it.

Sequence: a STOP holds the rotator for its marker; WSJT-X following is started in time under
the hold (unstamped); then a remote's ``track NOSUCH`` (stamped, 5 s expiry) is taken under
the same hold, its look-up answered at once with "no such satellite" (nothing changes); the
marker comes back 8 s later. Taken late with no hold, the look-up would be refused and
following would go on; in time, it would have failed and following would go on. Here
following ends ("tracking ended: its expiry passed") and the rotor never turns to the QSO
partner."""

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
    reason=(
        "review 37: a stamped look-up track start held past its expiry ends following it "
        "never ended (session.py _waited, rule 13)"
    ),
)
def test_a_late_look_up_under_a_hold_leaves_following_begun_before_it_alone(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    v = starts_rig(rig, monkeypatch)
    t = v.now
    path = iss_tle(v, tmp_path)
    following_under_a_hold(v)
    lookup = LookupQuestion(TleCatalog(path), "nosuch")  # a name the file does not have
    v.mailbox.put_track(
        Track(None, Source.MQTT, lookup, described="track nosuch", not_after_s=v.now + 5.0)
    )
    v._take()
    v.run_for(8.0)
    assert v.status.following is not None  # (the look-up failed: nothing changed)
    v.mailbox.put_release(1)  # the marker back, past the look-up's expiry
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert v.status.following is not None, said
    assert bearings(v, since=t) != [], said  # the rotor turns to the QSO partner
