"""app.py rule 6's look at a rotor that may turn (``Rotator.may_turn``), read from the main
thread while the serial-lines thread applies what the mailbox holds: the lines thread writes the
status first and then the place it shows commands up to (session.py ``newest_applied``), so a
look that read them the other way round, with a target applied between its two reads, saw
neither the turn nor the target on its way, and the end's first look left the rotor turning."""

from __future__ import annotations

from dataclasses import replace

import pytest

from bridge.app import worker_config
from bridge.core.model import MotionState, RotatorStatus, Target
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.runtime.worker import Worker
from bridge.settings import RotatorSettings


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
