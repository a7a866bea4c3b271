"""Review 69: 3e65c148 has check-config read the cty file with the start's own ``read_cty``, and
then drops what that reading refused: an entity whose place no place has (cty.py rule 5, a hand
edit's slip, ``357.0`` for ``35.70``), which the start logs at WARNING ("its calls are placed
nowhere"), is not in check-config's warnings, which are there for "what is allowed but probably
wrong". check-config says "config OK" of the file, having read the very line the start will
warn of."""

from __future__ import annotations

from pathlib import Path

from tests.dxcluster.cty_sample import CTY_DAT
from tests.support import cli, to_toml

SLIP = "Palau:                    27:  64:  OC:   357.0:  -134.53:    -9.0:  T8:\n    T8;\n"


def test_check_config_warns_of_an_entity_the_start_will_place_nowhere(tmp_path: Path) -> None:
    cty = tmp_path / "cty.dat"
    cty.write_text(CTY_DAT + SLIP)
    config = tmp_path / "bridge.toml"
    config.write_text(
        to_toml(
            {
                "state_file": tmp_path / "state.json",
                "mqtt": {"host": "127.0.0.1"},
                "station": {"locator": "JO01"},
                "dxcluster": {
                    "enabled": True,
                    "host": "dx.example.org",
                    "login": "G4ABC",
                    "cty_file": cty,
                },
                "rotators": [{"id": "tower", "model": "rotorez", "port": "/dev/rotor"}],
            }
        )
    )
    out = cli("check-config", "-c", str(config))
    assert out.returncode == 0, out.stderr
    warned = [line for line in out.stdout.splitlines() if line.startswith("warning: dxcluster.")]
    assert any("Palau" in line and "357.0" in line for line in warned), out.stdout
