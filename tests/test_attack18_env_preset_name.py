"""Attack 18: a preset set from the environment by its name
(``ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU=50``, "any value can also come from the
environment", README) does not change the file's preset ``EU``: the variable's path is read in
lower case, so it adds a second preset ``eu`` beside the file's ``EU = 45``. Home Assistant's
select and R/presets show both, and ``EU`` still turns the antenna to 45."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

from tests.support import cli, to_toml


def test_a_preset_set_from_the_environment_by_name_replaces_the_files(tmp_path: Path) -> None:
    out = check(tmp_path, {"EU": 45}, {"ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU": "50"})
    assert out.returncode == 0, out.stderr
    assert presets_shown(out.stdout) == {"EU": 50.0}


def test_a_preset_the_file_lacks_is_added_as_the_variable_spells_it(tmp_path: Path) -> None:
    """The select shows the name the user wrote, not a lower-cased one."""
    env = {"ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__JA": "330"}
    out = check(tmp_path, {"EU": 45}, env)
    assert out.returncode == 0, out.stderr
    assert presets_shown(out.stdout) == {"EU": 45.0, "JA": 330.0}


def test_a_name_two_presets_share_but_for_case_is_refused_naming_both(tmp_path: Path) -> None:
    """Which of ``EU`` and ``eu`` a variable means cannot be told (its name is read in any
    case): one line naming both, exit code 2, not one of them changed at random."""
    out = check(tmp_path, {"EU": 45, "eu": 50}, {"ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU": "60"})
    assert out.returncode == 2, out
    assert "config OK" not in out.stdout
    said = [
        line
        for line in out.stderr.splitlines()
        if "ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU" in line
    ]
    assert said and "'EU'" in said[0] and "'eu'" in said[0], out.stderr


def test_an_az_el_preset_set_by_name_takes_its_two_numbers_in_json(tmp_path: Path) -> None:
    """``[azimuth, elevation]`` as the table's other lists are given (docs/configuration.md);
    the text itself was refused as no number."""
    env = {"ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__SAT": "[180, 45]"}
    out = check(tmp_path, {"EU": 45}, env, model="gs232b")
    assert out.returncode == 0, out.stderr
    assert presets_shown(out.stdout) == {"EU": 45.0, "SAT": [180.0, 45.0]}


def test_a_preset_set_by_name_to_no_bearing_is_one_line_naming_its_variable(
    tmp_path: Path,
) -> None:
    """settings/errors.py rule 1: pydantic's union of a number and a list gave two lines, each
    named after a branch (``rotators[0].presets.EU.float``, ``...EU.list[float]``), and neither
    named the variable."""
    out = check(tmp_path, {"EU": 45}, {"ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU": "abc"})
    assert out.returncode == 2, out
    said = [line.strip() for line in out.stderr.splitlines()[1:] if line.strip()]
    assert said == [
        "rotators[0].presets.EU (from ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU): a preset is a "
        "bearing (a number) or [azimuth, elevation]"
    ], out.stderr


def test_a_preset_of_no_bearing_in_the_file_is_one_line_naming_it(tmp_path: Path) -> None:
    out = check(tmp_path, {"EU": "abc"}, {})
    assert out.returncode == 2, out
    said = [line.strip() for line in out.stderr.splitlines()[1:] if line.strip()]
    assert said == [
        "rotators[0].presets.EU: a preset is a bearing (a number) or [azimuth, elevation]"
    ], out.stderr


def check(
    tmp_path: Path, presets: dict[str, Any], env: dict[str, str], model: str = "rotorez"
) -> subprocess.CompletedProcess[str]:
    config = tmp_path / "bridge.toml"
    rotator = {"id": "tower", "model": model, "port": str(tmp_path / "tty"), "presets": presets}
    document = {
        "state_file": str(tmp_path / "state.json"),
        "mqtt": {"host": "127.0.0.1"},
        "rotators": [rotator],
    }
    config.write_text(to_toml(document))
    return cli("check-config", "--full", "-c", str(config), env=env)


def presets_shown(stdout: str) -> Any:
    """The rotator's presets as check-config --full shows them."""
    start = stdout.index('"presets": {')
    end = stdout.index("}", start) + 1
    return json.loads(stdout[start + len('"presets": ') : end])
