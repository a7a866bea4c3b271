from __future__ import annotations

import json
from pathlib import Path

from bridge.engine.state_store import StateStore


def test_lock_and_options_survive_a_restart(tmp_path: Path) -> None:
    path = tmp_path / "sub" / "state.json"
    s = StateStore(path)
    assert s.locked("tower") is False and s.options("tower") == {}
    s.set_locked("tower", True)
    s.set_option("tower", "jam", False)
    again = StateStore(path)
    assert again.locked("tower") is True and again.options("tower") == {"jam": False}
    assert again.locked("other") is False
    assert json.loads(path.read_text())["rotators"]["tower"]["locked"] is True


def test_an_unreadable_state_file_starts_every_rotator_locked(tmp_path: Path) -> None:
    path = tmp_path / "state.json"
    path.write_text("{not json")
    s = StateStore(path)
    assert s.locked("tower") is True and s.locked("yagi") is True  # safety before convenience
    assert s.set_locked("tower", False) is True  # the user unlocks one explicitly
    again = StateStore(path)
    assert again.locked("tower") is False
    assert again.locked("yagi") is True  # still locked after the restart: nobody unlocked it


def test_a_lock_that_cannot_be_saved_says_so(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    s = StateStore(blocker / "state.json")  # its directory cannot be created
    assert s.set_locked("tower", True) is False
