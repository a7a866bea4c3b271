"""Review 92 (runtime/kept.py rule 12, interfaces/mqtt/remote.py rule 10): the save of the
places that was queued before a lock ON (a target's turn place) runs after the session showed
the lock word's place, writes that place, and writes the lock as it was: the lock ON's own
save comes next. A power cut (or kill) between the two writes, one fsync on a slow SD card,
leaves a state file that keeps the lock ON's place but not the lock. The next run shows the
rotator unlocked with ``order.lock`` at the ON's place, past what a remote's held lock ON was
stamped against, so the remote takes its lock ON as overtaken by a newer lock word and drops
it instead of sending it again: the tower is left unlocked. Before rule 12 the new run showed
lock place 0 and the remote sent its lock ON again. Real parts: the state file on disk, the
rotator's Kept fed the statuses its session shows, the remote's own ``held_stamp``; the
writer's jobs run by hand in their order (a slow writer), a fake steady clock."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.core.model import Order
from bridge.interfaces.mqtt.remote import held_stamp
from bridge.runtime.kept import ORDER_SAVE_S
from bridge.runtime.state_store import StateStore
from tests.engine.test_review92_state_file_written_per_target import Steady, towers_kept


def test_a_lock_ons_place_is_never_kept_without_the_lock(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path, clock = tmp_path / "state.json", Steady()
    store = StateStore(path)
    jobs: list[Callable[[], None]] = []  # the writer's line, run by hand: a slow writer
    monkeypatch.setattr(store, "later", jobs.append)
    monkeypatch.setattr(store, "queue", jobs.append)
    kept = towers_kept(store, clock)
    kept.seen_order(Order("run1", 0, 0, 0, 0))  # the run's first status
    kept.seen_order(Order("run1", 1, 1, 0, 0))  # a target at place 1: the places' save queued
    kept.set_lock(True)  # the remote's lock ON, at place 2: its own save queued behind
    clock.now += ORDER_SAVE_S + 0.1  # (the writer still in an earlier fsync)
    kept.seen_order(Order("run1", 2, 1, 2, 0))  # the session took the lock word at place 2
    jobs.pop(0)()  # the places' save
    # the power is cut here, before the lock ON's save
    after = StateStore(path)
    since, _, lock_place = after.order("tower")
    stamp = held_stamp({"run1": (1,)}, "run2", since, since)  # the remote saw place 1 before it
    assert after.locked("tower") or lock_place <= stamp, (
        f"the next run shows the lock OFF with the lock word's place {lock_place}, past the "
        f"remote's held lock ON's stamp {stamp}: the remote drops it"
    )
