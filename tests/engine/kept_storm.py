"""Set-up shared by the kept-storm reviews (104, 106, 109): a run's statuses saved to the state
file as runtime/rotator.py ``_status`` saves them (kept.py rules 4, 12), and a new run's
session built from what the state file kept, as runtime/rotator.py starts it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bridge.runtime.kept import Kept
from bridge.runtime.state_store import StateStore
from bridge.session.session import RotatorSession
from tests.engine.virtual import VirtualRotator


def saved(v: VirtualRotator, path: Path, begun: int = 0, *, timed: bool = False) -> StateStore:
    """The state file at ``path`` as one run's statuses (from ``begun``) left it, each handed to
    Kept as runtime/rotator.py ``_status`` does; ``timed``: Kept's clock at each status's time.
    Returns the flushed store."""
    store, clock = StateStore(path), [0.0]
    if timed:
        memory = Kept(
            store, v.cfg.rotator_id, v.cfg.spec, report=lambda *a: None, clock=lambda: clock[0]
        )
    else:
        memory = Kept(store, v.cfg.rotator_id, v.cfg.spec, report=lambda *a: None)
    for t, status in v.statuses[begun:]:
        clock[0] = t
        memory.seen_wind(status.wind)
        memory.seen_order(status.order)
    store.flush()
    return store


def kept(v: VirtualRotator, path: Path) -> Kept:
    """What a new run reads back from the state file at ``path``."""
    return Kept(StateStore(path), v.cfg.rotator_id, v.cfg.spec, report=lambda *a: None)


def session_from(v: VirtualRotator, again: Kept, **more: Any) -> RotatorSession:
    """A new run's session from what ``again`` kept: its storm and its order's places (``more``
    for the rest, e.g. ``locked`` or ``place``)."""
    return RotatorSession(
        v.cfg,
        storm=again.storm,
        storm_halted=again.storm_halted,
        storm_arrived=again.storm_arrived,
        storm_place=again.storm_place,
        order=(again.since, again.turn_place, again.lock_place),
        **more,
    )
