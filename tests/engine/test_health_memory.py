"""Rotor health's memory to the state file (health_memory.py), in virtual time: what is written
when, with the state file's writer run at once."""

from __future__ import annotations

from pathlib import Path

from bridge.core.model import RotatorHealth
from bridge.runtime.health_memory import SAVE_S, HealthMemory
from bridge.runtime.state_store import StateStore
from tests.support.clock import FakeClock


class Store(StateStore):
    """The real state file, with its writer thread replaced by doing the job at once."""

    def later(self, job):  # type: ignore[no-untyped-def]
        job()


def report(moves: int) -> RotatorHealth:
    return RotatorHealth(moves=moves, memory={"moves": moves})


def kept(path: Path) -> object:
    return StateStore(path).health("tower")


def test_reports_are_written_at_most_once_a_minute_and_the_last_at_stop(tmp_path: Path) -> None:
    clock = FakeClock()
    path = tmp_path / "state.json"
    memory = HealthMemory(Store(path), "tower", clock)
    memory.seen(report(5))  # the memory read back at start: not news
    assert kept(path) is None
    memory.seen(report(6))
    assert kept(path) == {"moves": 6}
    clock.t += SAVE_S / 2
    memory.seen(report(7))  # within the minute: held
    assert kept(path) == {"moves": 6}
    memory.flush()  # the rotator stops
    assert kept(path) == {"moves": 7}


def test_the_report_after_a_reset_is_written_at_once(tmp_path: Path) -> None:
    clock = FakeClock()
    path = tmp_path / "state.json"
    memory = HealthMemory(Store(path), "tower", clock)
    memory.seen(report(5))
    memory.seen(report(6))
    clock.t += 1.0
    memory.reset()
    memory.seen(report(0))  # the new baseline, a second after the last write
    assert kept(path) == {"moves": 0}
