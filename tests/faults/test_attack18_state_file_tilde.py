"""Attack 18: ``state_file`` written with a ``~`` (the way docs/configuration.md writes its own
default, ``~/.local/state/rotor-bridge/state.json``) is not the file in the home folder: the
bridge keeps its state, and the installation's lock (state_store.py rule 7), in a folder named
``~`` under whatever directory it was started from. Two runs of one configuration started
from two directories both start, under one client id (settings derive it from the expanded
path), and throw each other off the broker, the stops' connections too."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from bridge.runtime.state_store import held
from tests.support import to_toml, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.process import bridge_env


def test_a_state_file_under_home_written_with_a_tilde_is_held_there(
    tmp_path: Path, broker: Mosquitto
) -> None:
    home, elsewhere = tmp_path / "home", tmp_path / "elsewhere"
    kept = home / "rb" / "state.json"
    kept.parent.mkdir(parents=True)
    elsewhere.mkdir()
    config = tmp_path / "bridge.toml"
    config.write_text(
        to_toml(
            {
                "state_file": "~/rb/state.json",
                "mqtt": {"host": "127.0.0.1", "port": broker.port},
                "rotators": [{"id": "tower", "model": "rotorez", "port": str(tmp_path / "tty")}],
            }
        )
    )
    with held(kept):  # this installation's bridge runs (the test holds its lock)
        second = subprocess.Popen(
            [sys.executable, "-m", "bridge", "run", "-c", str(config)],
            cwd=str(elsewhere),
            env=bridge_env({"HOME": str(home)}),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:  # refused at once, or started with a state file of its own
            wait_until(
                lambda: second.poll() is not None or (elsewhere / "~").exists(),
                what="the second run to end or to write a state file",
            )
        finally:
            if second.poll() is None:
                second.terminate()
            _, err = second.communicate()
    assert not (elsewhere / "~").exists(), "the state file was made under the working directory"
    assert second.returncode == 2, err
    assert "another rotor-bridge runs this installation" in err, err
