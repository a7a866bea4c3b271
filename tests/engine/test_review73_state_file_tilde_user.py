"""Review 73 (fbf6d6c1, state_store.py rule 13): the leftover of a state file an earlier
version kept under a folder of the working directory is looked for at ``./~/<the path below
the home folder>`` alone, from the path already expanded. Before settings/base.py rule 7 every
``~`` was a folder's name, ``~user`` too: ``state_file = "~rotor/rb/state.json"`` (the service
user's home named by its user, as a unit run by another user names it) was kept at
``./~rotor/rb/state.json``, and rule 7 expands it to that user's home as ``~/...`` is. The
update reads no leftover for it and says nothing: a rotator locked there for tower work starts
unlocked, as review 69 found for ``~/...``."""

from __future__ import annotations

import json
import os
import pwd
import secrets
from pathlib import Path

import pytest

from bridge.app import App
from bridge.settings import Settings


def test_a_lock_kept_where_earlier_versions_kept_a_tilde_user_state_file_still_locks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    me = pwd.getpwuid(os.getuid())  # (a user of this system: ~user must name one)
    below = Path(f"rb-review73-{secrets.token_hex(4)}") / "state.json"  # (nothing there)
    home = Path(me.pw_dir)
    monkeypatch.setenv("HOME", str(home))  # the service user's own home, as systemd sets it
    monkeypatch.chdir(tmp_path)  # the directory the bridge runs from, before and after
    old = tmp_path / f"~{me.pw_name}" / below  # where the earlier version kept it
    old.parent.mkdir(parents=True)
    old.write_text(json.dumps({"rotators": {"tower": {"locked": True}}}))
    settings = Settings(
        state_file=f"~{me.pw_name}/{below}",
        rotators=[{"id": "tower", "model": "rotorez", "port": str(tmp_path / "tty")}],
    )
    assert settings.state_file == home / below  # (rule 7: the home folder's)
    assert not settings.state_file.exists()  # (not there yet: rule 13's case)
    app = App(settings)  # built, never started: no broker, no serial port, nothing written
    assert app.store.locked("tower"), f"the lock kept at {old} was not read"
