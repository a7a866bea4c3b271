"""Attack 18: a preset set from the environment by its name
(``ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU=50``, "any value can also come from the
environment", README) does not change the file's preset ``EU``: the variable's path is read in
lower case, so it adds a second preset ``eu`` beside the file's ``EU = 45``. Home Assistant's
select and R/presets show both, and ``EU`` still turns the antenna to 45."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.support import cli, to_toml


@pytest.mark.xfail(
    strict=True,
    reason="attack 18: ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU=50 adds a preset 'eu' and "
    "leaves the file's EU at 45",
)
def test_a_preset_set_from_the_environment_by_name_replaces_the_files(tmp_path: Path) -> None:
    config = tmp_path / "bridge.toml"
    config.write_text(
        to_toml(
            {
                "state_file": str(tmp_path / "state.json"),
                "mqtt": {"host": "127.0.0.1"},
                "rotators": [
                    {
                        "id": "tower",
                        "model": "rotorez",
                        "port": str(tmp_path / "tty"),
                        "presets": {"EU": 45},
                    },
                ],
            }
        )
    )
    out = cli(
        "check-config",
        "--full",
        "-c",
        str(config),
        env={"ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU": "50"},
    )
    assert out.returncode == 0, out.stderr
    start = out.stdout.index('"presets": {')
    presets = json.loads(out.stdout[start + len('"presets": ') : out.stdout.index("}", start) + 1])
    assert presets == {"EU": 50.0}, presets
