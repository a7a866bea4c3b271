"""Review 69: 9820130f (settings/base.py rule 7) moved ``state_file = "~/..."`` from where every
earlier version kept it, a folder named ``~`` under the working directory, to the home folder,
and says nothing of the file it leaves behind. An installation run from one directory (its own
home: ``./~/rb/state.json``) that was locked for tower work before the update starts unlocked
after it, its lock and the options set at run time in a file the bridge no longer reads; the
log, check-config and R/error say not a word of it. (The broker's retained ``R/lock/state`` ON
covers the lock alone, and only on a broker that kept it: here, as after a broker's restart
without persistence, it has none.)"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from tests.support import Probe, to_toml
from tests.support.mosquitto import Mosquitto
from tests.support.process import bridge_env


def tilde_installation(tmp_path: Path, broker: Mosquitto) -> tuple[Path, Path, Path]:
    """An installation run from its home folder: ``state_file = "~/rb/state.json"`` and the lock
    kept, as every earlier version kept it, at ``./~/rb/state.json``. (home, old file, config)"""
    home = tmp_path / "home"
    home.mkdir()
    old = home / "~" / "rb" / "state.json"  # run from the home folder, as before the update
    old.parent.mkdir(parents=True)
    old.write_text(json.dumps({"rotators": {"tower": {"locked": True}}}))
    config = tmp_path / "bridge.toml"
    config.write_text(
        to_toml(
            {
                "state_file": "~/rb/state.json",
                "mqtt": {"host": "127.0.0.1", "port": broker.port, "base_topic": "rotor"},
                "rotators": [{"id": "tower", "model": "rotorez", "port": str(tmp_path / "tty")}],
            }
        )
    )
    return home, old, config


def start_from_home(home: Path, config: Path) -> subprocess.Popen[str]:
    """``rotor-bridge run`` started from the home folder, with HOME set to it."""
    return subprocess.Popen(
        [sys.executable, "-m", "bridge", "run", "-c", str(config)],
        cwd=str(home),
        env=bridge_env({"HOME": str(home)}),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_a_lock_kept_where_earlier_versions_kept_a_tilde_state_file_still_locks(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    home, old, config = tilde_installation(tmp_path, broker)
    bridge = start_from_home(home, config)
    try:
        lock = probe.wait_for("rotor/lock/state", lambda m: m.text in ("ON", "OFF")).text
    finally:
        bridge.terminate()
        _, err = bridge.communicate()
    said = str(old) in err or "./~/rb/state.json" in err or "~/rb/state.json" in err
    assert lock == "ON" or said, f"R/lock/state {lock}, and the log says nothing of {old}:\n{err}"
    assert lock == "ON", f"R/lock/state {lock}: the lock kept at {old} was not read"
    assert json.loads((home / "rb" / "state.json").read_text())["rotators"]["tower"]["locked"]
