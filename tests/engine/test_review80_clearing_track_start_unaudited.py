"""Review 80: a track start a clearing hold ends is no refusal in the audit trail.

dbb4a840 (session.py rule 24) audits every drop of a command taken before it moved the rotor
as its sender's refusal, naming "a hold's that ends clearing (``_fence``, rule 13)" and "the
end of a stamped start under a hold (``_waited``)". A track start taken under a STOP's hold
and ended by its expiry is so audited (test_attack25_drops_audited). The same start ended by
the same hold *clearing* (the main MQTT connection lost before the stop's marker came back)
goes through ``_fence`` -> ``_end``: tracking ends with "a stop or lock came first; send the
track command again" in R/status ``tracking_ended``, nothing on R/error with its sender, and
the audit trail keeps ``track sun`` ``executed``, though the sender is told to send it again.

In virtual time: the real judge (runtime/rotator.py) with its audit listener, on the MD-01
bench of test_attack25_drops_audited."""

from __future__ import annotations

from pathlib import Path

from bridge.core.model import ErrorEvent, Source, Stop, TrackBody
from tests.engine.test_halt_epoch import Bench as Station
from tests.engine.test_lease_waiting_target import DL1ABC, G4XYZ

MARKER = 1
HELD_S = 1.0  # virtual: the hold goes on a while
AFTER_S = 5.0  # virtual


def test_a_track_start_a_clearing_hold_ends_is_refused_in_the_audit_trail(
    tmp_path: Path,
) -> None:
    station = Station(tmp_path)
    try:
        station.rot.submit(Stop(source=Source.MQTT, origin=DL1ABC), "stop", hold=MARKER)
        station.v._take()
        t = station.v.now
        station.rot.submit(TrackBody("sun", source=Source.MQTT, origin=G4XYZ), "track sun")
        station.v._take()
        assert station.v.status.tracking is not None  # taken, tracking under the hold
        station.v.run_for(HELD_S)
        station.rot.release(0, clear=True)  # the main connection dropped: the hold clears
        station.v._take()
        station.v.run_for(AFTER_S)
        assert station.v.status.tracking is None
        assert station.v.status.tracking_ended is not None
        assert "send the track command again" in station.v.status.tracking_ended
        for r in station.v.errors(since=t):  # as runtime/worker.py hands them to the judge
            station.rot._session_event(ErrorEvent(r.kind, r.message, r.command, 0.0, r.origin))
        refused = [(a.origin, a.command) for a in station.audit if a.result.startswith("refused")]
        assert refused == [(G4XYZ, "track sun")], station.audit
    finally:
        station.rot.operators.stop()
        station.v.close()
