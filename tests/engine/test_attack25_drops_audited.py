"""Attack 25: every target the session drops before it went out is a refusal of its sender's
command in the audit trail (session.py rule 24), as a lease's drop was (rule 23): here the
drop of a stop's hold that ends clearing (``_fence``: the main MQTT connection dropped before
the stop's marker came back) and the end of a stamped track start by its expiry (``_waited``).
Before, both were said on R/error only, and the trail kept the command ``executed``.

In virtual time: the real judge (runtime/rotator.py) with its audit listener, on a virtual
Rotor-EZ (tests/engine/test_lease_waiting_target.py's bench)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.core.model import ErrorEvent, Origin, Source, Stop, TrackBody
from tests.engine.test_halt_epoch import Bench as Station
from tests.engine.test_lease_waiting_target import DL1ABC, G4XYZ, Tower

MARKER = 1


@pytest.fixture
def tower(tmp_path: Path) -> Iterator[Tower]:
    made = Tower(tmp_path)
    yield made
    made.close()


def _refused(tower: Tower, since: float) -> list[tuple[Origin, str]]:
    """The session's reports since ``since`` handed to the judge as its worker hands them
    (runtime/worker.py ``_do``: the bench records them instead); the audit's refusals."""
    for r in tower.v.errors(since=since):
        tower.rot._session_event(ErrorEvent(r.kind, r.message, r.command, 0.0, r.origin))
    return [(a.origin, a.command) for a in tower.audit if a.result.startswith("refused")]


def test_a_target_a_clearing_hold_drops_is_refused_in_the_audit_trail(tower: Tower) -> None:
    tower.rot.submit(Stop(source=Source.MQTT, origin=DL1ABC), "stop", hold=MARKER)
    tower.take()
    t = tower.v.now
    tower.target(300, G4XYZ)  # waits for the stop's place in line (the hold)
    tower.rot.release(0, clear=True)  # the main connection dropped: the hold clears
    tower.take()
    tower.v.run_for(tower.v.cfg.motion.brake_delay_s + 3)
    assert tower.sets(since=t) == []  # the rotor was never sent to 300
    said = tower.v.errors("refused", since=t)
    assert [(r.command, r.origin) for r in said] == [("target az 300", G4XYZ)]
    assert [a.result for a in tower.audit if a.command == "target '300'"] == ["executed"]
    assert _refused(tower, t) == [(G4XYZ, "target az 300")], tower.audit


def test_a_track_start_ended_by_its_expiry_is_refused_in_the_audit_trail(tmp_path: Path) -> None:
    station = Station(tmp_path)  # (an MD-01 with the station's position: the sun is up)
    try:
        station.rot.submit(Stop(source=Source.MQTT, origin=DL1ABC), "stop", hold=MARKER)
        station.v._take()
        t = station.v.now
        late = t + 1.0  # the start's expiry: it passes while the hold goes on
        track = TrackBody("sun", source=Source.MQTT, origin=G4XYZ, not_after_s=late)
        station.rot.submit(track, "track sun")
        station.v._take()
        assert station.v.status.tracking is not None  # taken, tracking under the hold
        station.v.run_for(2.0)
        station.rot.release(MARKER)  # the stop's marker back, past the start's expiry
        station.v._take()
        assert station.v.status.tracking is None
        said = station.v.errors("refused", since=t)
        assert [(r.command, r.origin) for r in said] == [("track sun", G4XYZ)], said
        for r in said:  # handed to the judge as its worker hands them (runtime/worker.py)
            station.rot._session_event(ErrorEvent(r.kind, r.message, r.command, 0.0, r.origin))
        refused = [(a.origin, a.command) for a in station.audit if a.result.startswith("refused")]
        assert refused == [(G4XYZ, "track sun")], station.audit
    finally:
        station.rot.operators.stop()
        station.v.close()
