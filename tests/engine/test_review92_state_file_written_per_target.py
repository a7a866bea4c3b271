"""Review 92 (runtime/kept.py rule 12): a steady stream of targets, one a second (Gpredict or
any rotctld client tracking a satellite, PstRotator, a logger's script), writes the state file
once per target: each target's place is a new ``turn`` place and a second is past
ORDER_SAVE_S, so every one fsyncs the whole file. Before rule 12 a target wrote nothing; a
pass of hours on a Raspberry Pi's SD card is thousands of full rewrites an hour, for a place
that only a remote's held halt after a restart reads. Real parts: the state file on disk,
the rotator's Kept fed the statuses its session shows; a fake steady clock (virtual time)."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.app import worker_config
from bridge.core.model import ErrorKind, Order
from bridge.runtime.kept import Kept
from bridge.runtime.state_store import StateStore
from bridge.settings import RotatorSettings


class Steady:
    """A fake steady clock: ``now`` moved by hand."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def towers_kept(store: StateStore, clock: Steady) -> Kept:
    """The Kept of a Rotor-EZ ``tower`` on ``store``, timed by ``clock``; any report it makes
    fails the test."""
    spec = worker_config(RotatorSettings(id="tower", model="rotorez", port="/dev/null")).spec

    def report(kind: ErrorKind, message: str, what: str | None) -> None:
        raise AssertionError(message)

    return Kept(store, "tower", spec, report=report, clock=clock)


def test_a_target_every_second_does_not_write_the_state_file_each_time(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path, clock = tmp_path / "state.json", Steady()
    kept = towers_kept(StateStore(path), clock)
    store = kept._store
    kept.seen_order(Order("run1", 0, 0, 0, 0))  # the run's first status
    kept.seen_order(Order("run1", 1, 1, 0, 0))  # the first target: this run's block reserved
    store.flush()
    writes: list[float] = []
    real = StateStore._write

    def counted(self: StateStore, at: Path, *, put_in_place: bool = True) -> None:
        writes.append(clock.now)
        real(self, at, put_in_place=put_in_place)

    monkeypatch.setattr(StateStore, "_write", counted)
    seconds = 600  # ten minutes of a pass, one target a second
    for n in range(2, seconds + 2):
        clock.now += 1.0
        kept.seen_order(Order("run1", n, n, 0, 0))  # the status showing that target taken
        store.flush()
    assert len(writes) <= seconds // 60, f"{len(writes)} state file writes for {seconds} targets"
