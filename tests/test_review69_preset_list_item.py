"""Review 69: b0c7141d made a preset that is neither a number nor a list one line naming the
preset, where pydantic's union gave two lines named after its branches
(``presets.EU.float``, ``presets.EU.list[float]``). An az/el preset, a list, whose elevation
is no number (``SAT = [180, "high"]``, ``[180, nan]``, or from the environment
``PRESETS__SAT='[180, "high"]'``) still passes the new check as a list and is still refused in
those two lines, neither of which is the key as the file spells it (settings rule 2: one line
per problem, naming the key)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support import cli


@pytest.mark.parametrize("elevation", ['"high"', "nan"])
def test_an_az_el_preset_whose_elevation_is_no_number_is_one_line_naming_it(
    tmp_path: Path, elevation: str
) -> None:
    config = tmp_path / "bridge.toml"
    config.write_text(
        f'state_file = "{tmp_path / "state.json"}"\n'
        '[mqtt]\nhost = "127.0.0.1"\n'
        '[[rotators]]\nid = "sky"\nmodel = "gs232b"\nport = "/dev/rotor"\n'
        f"presets = {{ SAT = [180, {elevation}] }}\n"
    )
    out = cli("check-config", "-c", str(config))
    assert out.returncode == 2, out.stdout
    lines = out.stderr.splitlines()
    assert lines[0] == "rotor-bridge: invalid configuration:", out.stderr
    assert len(lines) == 2, out.stderr  # one problem, one line
    assert lines[1].startswith("  rotators[0].presets"), out.stderr
    assert ".float" not in lines[1] and "list[float]" not in lines[1], out.stderr
