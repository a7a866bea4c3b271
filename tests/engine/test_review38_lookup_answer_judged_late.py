"""Review 38 on 04cdff24 (session.py rule 13): a satellite's look-up taken under a hold takes no
stamped start's place, "as it ends nothing until its answer": the two are judged as one, by the
sooner expiry. But the answer may come under the same hold, and then it does end what the
start before it began (feature_commands.py ``answered``: another body, the targets cleared):
the late start's motion is over, and what goes on is the satellite, asked for in time. The
hold's end still judges it by the late start's expiry, and the satellite's tracking, begun in
time from a command whose own expiry has not passed, is ended at the marker, said as the late
``track sun``'s end (the operator's ``track ISS`` is named nowhere).

Sequence: a STOP holds the rotator for its marker; a remote's ``track sun`` (stamped, 5 s
expiry) is taken under the hold; then ``track ISS (ZARYA)`` by name (stamped, 30 s expiry),
whose look-up is answered under the hold (tracking ISS); the marker comes back 8 s after the
sun's start, long before the ISS command's expiry. Rule 13: "The newest start taken under the
hold is the one judged: it ended what the one before it began"."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.core.model import Source, Stop
from bridge.session.tracking import Track
from bridge.sky import Body
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.test_session_last_word import iss_tle, starts_rig
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_a_satellite_asked_for_in_time_is_not_ended_for_a_late_start_before_it(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    v = starts_rig(rig, monkeypatch)
    t = v.now
    path = iss_tle(v, tmp_path)
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
    v.mailbox.put_track(Track(Body.sun(), described="track sun", not_after_s=t + 5.0))
    v._take()
    lookup = LookupQuestion(TleCatalog(path), "ISS (ZARYA)")
    iss = Track(None, Source.MQTT, lookup, described="track ISS", not_after_s=t + 30.0)
    v.mailbox.put_track(iss)
    v._take()
    v.run_for(8.0)
    assert v.status.tracking is not None and "ISS" in v.status.tracking.body  # (answered)
    v.mailbox.put_release(1)  # the marker back: past the sun's expiry, not the ISS command's
    v._take()
    v.run_for(2.0)
    said = [e.message for e in v.errors(since=t)]
    assert v.status.tracking is not None and "ISS" in v.status.tracking.body, said
