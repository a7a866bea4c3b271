"""Review 135 on 78f3d4fb (session.py rule 13): ``sky_answer`` tells a look-up's answer that
began tracking from one that began nothing by the body tracked before and after
(``self.tracker.body not in (None, body)``). A look-up of the satellite already tracked begins
tracking all the same (feature_commands.py ``track``: the old tracking ends, "another body",
and starts anew), but the new ``Body`` equals the old one (a frozen dataclass), so the answer is
read as "began nothing" and what waited before it, the in-time start, is put back. The late
start's tracking is no longer judged: the marker, past its expiry, ends nothing and the rotor
turns (rule 13: the newest start taken under the hold is the one judged; review 38: once a
look-up's answer begins tracking, it is judged alone). The parent (78f3d4fb^) ended it.

Sequence: a STOP holds the rotator for its marker; ``track ISS (ZARYA)`` (unstamped, in time)
under the hold, answered: tracking; ``track ISS (ZARYA)`` again, stamped with a 5 s expiry,
answered: tracking restarted; the marker back 8 s later."""

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


def test_a_late_look_up_of_the_satellite_tracked_under_the_hold_turns_nothing(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    v = starts_rig(rig, monkeypatch)
    t = v.now
    catalog = TleCatalog(iss_tle(v, tmp_path))
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
    v._take()
    look_up(v, catalog, "ISS (ZARYA)", None)  # in time, under the hold
    v.run_for(1.0)
    assert v.status.tracking is not None  # (its answer began tracking)
    look_up(v, catalog, "ISS (ZARYA)", v.now + 5.0)  # late: the marker comes 8 s later
    v.run_for(8.0)
    assert bearings(v, since=t) == []  # (held)
    v.mailbox.put_release(1)  # the marker back, past the second look-up's expiry
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert bearings(v, since=t) == [] and not v.truth().is_moving, said
    assert v.status.tracking is None, said
