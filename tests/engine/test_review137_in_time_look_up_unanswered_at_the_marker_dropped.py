"""Review 137 on 293e4123 (session.py rule 13): review 38's case with the sky worker a little
behind. A satellite's look-up asked for in time under a hold, after a late stamped start, is
judged alone once its answer begins tracking under the hold (review 38), and tracks. When the
marker comes before its answer, ``_waited`` judges the two as one by the late start's sooner
expiry and, the look-up being under way (``_began``), ends it too: the satellite asked for in time
is never tracked, and the only word is the late ``track sun``'s end. Answered 0.4 s sooner, the
same commands track the ISS. The parents (78f3d4fb^ and 78f3d4fb) have it too.

Sequence: a STOP holds the rotator for its marker; a remote's ``track sun`` stamped to expire at
5 s is taken under the hold; at 4.8 s ``track ISS (ZARYA)`` by name, stamped to expire at 30 s,
the sky worker answering 0.5 s after a question; the marker back at 5.1 s."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.core.model import Source, Stop
from bridge.session.tracking import Track
from bridge.sky import Body
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.test_session_last_word import bearings, iss_tle, starts_rig
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.xfail(
    strict=True,
    reason="review-137 2: a look-up sent in time, unanswered when the marker comes, is dropped "
    "for the expiry of a late start before it",
)
def test_a_satellite_asked_for_in_time_unanswered_at_the_marker_is_tracked(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    v = starts_rig(rig, monkeypatch)
    t = v.now
    catalog = TleCatalog(iss_tle(v, tmp_path))
    v.sky_delay_s = 0.5  # the sky worker a little behind (busy with another rotator's pass)
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
    v.mailbox.put_track(Track(Body.sun(), described="track sun", not_after_s=t + 5.0))
    v._take()
    v.run_for(4.8)
    lookup = LookupQuestion(catalog, "ISS (ZARYA)")
    iss = Track(None, Source.MQTT, lookup, described="track ISS", not_after_s=t + 30.0)
    v.mailbox.put_track(iss)
    v._take()
    v.run_for(0.3)
    assert bearings(v, since=t) == []  # (held)
    v.mailbox.put_release(1)  # the marker back: past the sun's expiry, not the ISS command's
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert v.status.tracking is not None and "ISS" in v.status.tracking.body, said
