"""Rotor health's memory in the state file (state_store.py): kept beside the lock and the
options, read back by a new store, and a health entry that is not a table is no memory."""

from __future__ import annotations

import json
from pathlib import Path

from bridge.runtime.state_store import StateStore


def test_health_memory_survives_a_new_store_beside_the_lock(tmp_path: Path) -> None:
    path = tmp_path / "state.json"
    store = StateStore(path)
    store.check_writable()
    assert store.set_locked("tower", True)
    assert store.set_health("tower", {"version": 1, "moves": 3})
    again = StateStore(path)
    assert again.health("tower") == {"version": 1, "moves": 3}
    assert again.locked("tower") is True
    assert again.health("other") is None


def test_a_health_entry_that_is_not_a_table_is_no_memory(tmp_path: Path) -> None:
    path = tmp_path / "state.json"
    path.write_text(json.dumps({"rotators": {"tower": {"locked": False, "health": [1, 2]}}}))
    store = StateStore(path)
    assert store.health("tower") is None
    assert store.locked("tower") is False and not store.corrupt
