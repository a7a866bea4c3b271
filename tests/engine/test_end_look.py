"""app.py rule 6's look at a rotor that may turn (``Rotator.may_turn``), read from the main
thread while the serial-lines thread applies what the mailbox holds: the lines thread writes the
status first and then the place it shows commands up to (session.py ``newest_applied``), so a
look that read them the other way round, with a target applied between its two reads, saw
neither the turn nor the target on its way, and the end's first look left the rotor turning.
And what the session does once told the end began (session.py rule 21): no part's next move,
but the storm's park."""

from __future__ import annotations

from dataclasses import replace

import pytest

from bridge.app import worker_config
from bridge.core.model import MotionState, RotatorStatus, Target
from bridge.emulators.spid import Outcome
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.runtime.worker import Worker
from bridge.settings import RotatorSettings
from bridge.sky import Body, Sky
from tests.engine.test_session_tracking import SUN_EPOCH, sun_up_somewhere
from tests.engine.test_wind import wind, windy
from tests.engine.virtual import VirtualRotator

SETS = (Outcome.SET, Outcome.SET_CLAMPED)  # a SPID's bearing frames


def test_a_target_applied_while_the_end_looks_is_seen_on_its_way_or_turning(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    settings = RotatorSettings.model_validate({"id": "t", "model": "md01", "port": "/dev/null"})
    rot = Rotator(worker_config(settings), StateStore(None), lambda s: None, lambda e: None)
    rot._mailbox.put(Target(100.0))  # judged and put; the lines thread has not taken it yet
    session = rot._worker.session
    before = session.status
    real = Worker.status

    def applied_after_this_read(worker: Worker) -> RotatorStatus:
        """The status as it was, then the lines thread takes the target and writes, in its
        order, the new status and the place it shows commands up to."""
        status = real.fget(worker)  # type: ignore[attr-defined]
        if status is before:
            session.status = replace(before, state=MotionState.MOVING)
            session._newest_taken = rot._mailbox.ticket()  # (at least the target's place)
        return status

    monkeypatch.setattr(Worker, "status", property(applied_after_this_read))
    try:
        assert rot.may_turn()  # stopped by the end's first look
    finally:
        rot.stop()


def test_once_told_the_end_began_tracking_sends_no_next_step() -> None:
    """session.py rule 21: the end's looks stop what may turn; a part's next move after them
    would turn the rotor with nobody left to stop it (tracking's next step, here, with no
    stop at all: the session's own rule, not the end's stop)."""
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall)
    with VirtualRotator(
        "md01",
        sky=Sky(lat, lon),
        wall_epoch_s=wall,
        emulator={"az_speed_deg_s": 2.0, "el_speed_deg_s": 1.0},
        settings={"az_speed_deg_s": 2.0, "el_speed_deg_s": 1.0},
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.sun())
        v.run_until(lambda h: len(h.frames(*SETS)) >= 2, 1800, "a step after the first turn")
        v.mailbox.put_ending()  # (runtime/rotator.py leave)
        v._take()
        v.run_until(lambda h: not h.truth().is_moving, 60, "the step under way ends")
        since, where = v.now, v.truth()
        v.run_for(3600.0)  # an hour: the sun moved several steps on
        assert v.frames(*SETS, since=since) == []
        assert (v.truth().az_deg, v.truth().el_deg) == (where.az_deg, where.el_deg)


def test_once_told_the_end_began_a_storms_park_still_goes() -> None:
    """session.py rule 21's exception (app.py rule 6): a storm's park goes on."""
    with windy() as v:
        v.mailbox.put_ending()
        v._take()
        wind(v, 90.0)
        v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
        assert abs(v.truth().az_deg - 90.0) <= 0.5
