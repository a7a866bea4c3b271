"""Review 86 (runtime/kept.py rule 12): the state file keeps a rotator's places in the order
of commands across restarts, and a flood of targets writes it a few times, not once per
target (an SD card's fsyncs, a lock word's save waiting behind them). Real parts: the state
file on disk, the rotator's Kept fed the statuses its session would show; a fake steady clock.
(The restart as a user sees it, on R/status: tests/mqtt/test_status_order.py.)"""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.app import worker_config
from bridge.core.model import ErrorKind, Order
from bridge.runtime.kept import ORDER_SAVE_S, PLACES_BLOCK, Kept
from bridge.runtime.state_store import StateStore
from bridge.settings import RotatorSettings


class Steady:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def _kept(path: Path, clock: Steady) -> Kept:
    spec = worker_config(RotatorSettings(id="tower", model="rotorez", port="/dev/null")).spec

    def report(kind: ErrorKind, message: str, what: str | None) -> None:
        raise AssertionError(message)

    return Kept(StateStore(path), "tower", spec, report=report, clock=clock)


def test_a_flood_of_targets_writes_the_state_file_a_few_times_not_per_target(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path, clock = tmp_path / "state.json", Steady()
    kept = _kept(path, clock)
    store = kept._store
    kept.seen_order(Order("run1", 0, 0, 0, 0))  # the run's first status: nothing saved
    store.flush()
    writes: list[float] = []
    real = StateStore._write

    def counted(self: StateStore, at: Path, *, put_in_place: bool = True) -> None:
        writes.append(clock.now)
        real(self, at, put_in_place=put_in_place)

    monkeypatch.setattr(StateStore, "_write", counted)
    targets = 500
    for n in range(1, targets + 1):  # a dragged slider: 500 targets in one second
        clock.now += 1.0 / targets
        kept.seen_order(Order("run1", n, n, 0, 0))
        store.flush()  # (a fast writer: each save done before the next target)
    assert 0 < len(writes) <= 1 / ORDER_SAVE_S + 1, f"{len(writes)} writes for {targets} targets"
    clock.now += ORDER_SAVE_S
    kept.seen_order(Order("run1", targets, targets, 0, 0))  # the turn's next reading
    store.flush()
    assert StateStore(path).order("tower") == (1 + PLACES_BLOCK, targets, 0)


def test_a_restart_counts_on_after_the_block_reserved_and_reserves_the_next_in_time(
    tmp_path: Path,
) -> None:
    path, clock = tmp_path / "state.json", Steady()
    first = _kept(path, clock)
    assert first.since == 0
    taken = PLACES_BLOCK // 2 + 1  # half the block taken: the next reserved at once
    first.seen_order(Order("run1", taken, taken, 3, 0))
    first._store.flush()
    second = _kept(path, clock)  # the bridge killed there, and started again
    assert second.since >= taken
    assert (second.turn_place, second.lock_place) == (taken, 3)
