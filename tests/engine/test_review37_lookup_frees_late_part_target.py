"""Review 37 on c222c9df (session.py rule 13): a feature's command that moves, stamped and taken
under a hold, is the start judged when the hold ends; past its expiry the target its part
proposed is dropped (``_waited``: ``waiting.part``). A later start under the same hold takes its
place (``_wait``), on the ground that it ended what the one before began. A track start by a
satellite's name (a look-up) does not: it ends the parts' own motion but leaves the target
waiting (feature_commands.py ``track``: whatever goes on goes on until the answer), and it
forgets the late command all the same. When the hold ends past the command's expiry nothing
is judged, and the rotor turns to the target of a command whose expiry passed while it waited
for the order of a STOP.

Sequence: a STOP holds the rotator for its marker; a remote's ``beam aim 200`` (stamped, 5 s
expiry) is taken under the hold, its part proposing 200; then an unstamped ``track nosuch``
(a name the TLE file does not have: "no satellite", nothing changes); the marker comes back
8 s later. Without the look-up the 200 is dropped, said (test_session_last_word.py); with it,
the rotor turns to 200 after the STOP, 8 s after it was sent with a 5 s expiry. So does
tracking a late stamped ``track sun`` began (second test: built-in features alone)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.core.model import FeatureCommand, Source, Stop
from bridge.session.tracking import Track
from bridge.sky import Body
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.test_session_last_word import bearings, iss_tle, starts_rig
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_a_look_up_under_the_hold_does_not_let_a_late_commands_target_go(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    v = starts_rig(rig, monkeypatch)
    t = v.now
    path = iss_tle(v, tmp_path)
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
    aim = FeatureCommand(feature="beam", name="aim", value=200.0, not_after_s=t + 5.0)
    v.mailbox.put_feature(aim)  # stamped, taken under the hold
    v._take()
    lookup = LookupQuestion(TleCatalog(path), "nosuch")
    v.mailbox.put_track(Track(None, Source.MQTT, lookup, described="track nosuch"))
    v._take()
    v.run_for(8.0)
    assert bearings(v, since=t) == []  # (held)
    v.mailbox.put_release(1)  # the marker back, past the aim's expiry
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert bearings(v, since=t) == [] and not v.truth().is_moving, said


def test_a_look_up_under_the_hold_does_not_let_a_late_track_start_turn_the_rotor(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """The same with no feature of a test's own: a remote's ``track sun`` (stamped, 5 s expiry)
    taken under the hold, then an unstamped ``track nosuch``; the look-up leaves the sun
    tracked ("until the answer"; it fails) and takes the late start's place, so the marker back
    8 s later ends nothing and tracking turns the rotor to the sun."""
    v = starts_rig(rig, monkeypatch)
    t = v.now
    path = iss_tle(v, tmp_path)
    v.mailbox.put(Stop(Source.MQTT), hold=1)
    v.mailbox.put_track(Track(Body.sun(), described="track sun", not_after_s=t + 5.0))
    v._take()
    lookup = LookupQuestion(TleCatalog(path), "nosuch")
    v.mailbox.put_track(Track(None, Source.MQTT, lookup, described="track nosuch"))
    v._take()
    v.run_for(8.0)
    assert bearings(v, since=t) == []  # (held)
    v.mailbox.put_release(1)  # the marker back, past the track start's expiry
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert bearings(v, since=t) == [] and not v.truth().is_moving, said
    assert v.status.tracking is None, said
