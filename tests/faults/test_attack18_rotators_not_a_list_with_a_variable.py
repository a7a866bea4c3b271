"""Attack 18: a ``rotators`` key that is no list (``rotators = 5``, a date, true) together with a
rotator's variable (``ROTOR_BRIDGE_ROTATORS__TOWER__PORT``, the README's own example) ends
check-config and run in a TypeError traceback, exit code 1 (systemd restarts it every 5 s for
ever), instead of one line naming ``rotators`` and exit code 2. The same file without the
variable is the usual one-line error."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support import run_cli


@pytest.mark.parametrize(
    "variable",
    ["ROTOR_BRIDGE_ROTATORS__TOWER__PORT", "ROTOR_BRIDGE_ROTATORS__TOWERPORT"],
    ids=["a rotator's key", "no rotator's key"],
)
def test_rotators_not_a_list_with_a_rotator_variable_is_one_line_naming_rotators(
    tmp_path: Path, variable: str
) -> None:
    config = tmp_path / "bridge.toml"
    config.write_text(
        f'state_file = "{tmp_path / "state.json"}"\nrotators = 5\n\n[mqtt]\nhost = "127.0.0.1"\n'
    )
    out = run_cli("check-config", "-c", str(config), env={variable: str(tmp_path / "tty")})
    assert "Traceback" not in out.stderr, out.stderr
    assert out.returncode == 2, out
    said = [line for line in out.stderr.splitlines() if line.strip()]
    assert any("rotators" in line for line in said), out.stderr
