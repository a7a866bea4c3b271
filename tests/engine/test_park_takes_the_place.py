"""A park takes the place of the turn it finds (session/targets.py rule 9): an axis it leaves
out (no ``park_el_deg``) holds where it reads, never the axis of a target that was waiting
when the park came, whoever sent the two (core/model.py ``combine``)."""

from __future__ import annotations

from bridge.core.model import Source, Target
from tests.engine.virtual import VirtualRotator

SLOW = {"az_speed_deg_s": 10.0, "el_speed_deg_s": 2.0}


def gs232b() -> VirtualRotator:
    return VirtualRotator(
        "gs232b", settings={**SLOW, "park_az_deg": 0}, emulator={**SLOW, "start_az_deg": 200}
    )


def test_a_park_after_a_waiting_target_does_not_take_its_elevation() -> None:
    """An attack pass: 100/10, then 300/40 from the same MQTT sender within the stream's
    pause (targets.py rule 2: it waits), then R/park: the park took the waiting target's
    elevation (``combine``) and went out as ``W000 040``, the elevation turned from about 0 to
    40 for a park configured to leave it as it is."""
    with gs232b() as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(100.0, 10.0)
        v.run_for(0.1)
        v.target(300.0, 40.0)  # within BURST_QUIET_S of the one sent: it waits
        v.run_for(0.1)
        v.command(Target(0.0, None, Source.MQTT, park=True))
        v.run_until(lambda h: h.status.parked, 120, "parked")
        v.run_for(30)
        sets = [w for w in v.sent() if w.startswith(b"W")]
        assert sets[0] == b"W100 010\r" and not any(w.endswith(b" 040\r") for w in sets), sets
        assert v.truth().el_deg <= 1.0, v.truth()
        assert abs(v.truth().az_deg) <= 1.0, v.truth()


def test_a_park_in_the_batch_of_a_target_does_not_take_its_elevation() -> None:
    """The same in one batch of the mailbox (mailbox.py rule 2): 300/40 and then R/park from
    one sender, taken together, went out as one ``W000 040``."""
    with gs232b() as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.command(Target(300.0, 40.0), Target(0.0, None, Source.MQTT, park=True))
        v.run_until(lambda h: h.status.parked, 120, "parked")
        v.run_for(30)
        sets = [w for w in v.sent() if w.startswith(b"W")]
        assert not any(w.endswith(b" 040\r") for w in sets), sets
        assert v.truth().el_deg <= 1.0, v.truth()
