"""Attack 18: a cty file that can be read but holds no entity (an HTML error page saved by a
download that failed, another file named by mistake) passes check-config ("(found)", "config
OK"), and the start then stops on it, exit code 2: "cty_file ...: no entity in it". An attack
pass made check-config refuse a cty file the start cannot read; one the start cannot use is
the same promise (README: check-config says what the bridge would do with the file)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support import cli, run_cli, to_toml


def _config(tmp_path: Path) -> Path:
    cty = tmp_path / "cty.dat"
    cty.write_text("<html><head><title>404 Not Found</title></head></html>\n")
    config = tmp_path / "bridge.toml"
    config.write_text(
        to_toml(
            {
                "state_file": str(tmp_path / "state.json"),
                "mqtt": {"host": "127.0.0.1", "port": 1},
                "dxcluster": {
                    "enabled": True,
                    "host": "dxc.example.org",
                    "login": "G4ABC",
                    "cty_file": str(cty),
                },
                "rotators": [{"id": "tower", "model": "rotorez", "port": str(tmp_path / "tty")}],
            }
        )
    )
    return config


def test_the_start_stops_on_a_cty_file_without_entities(tmp_path: Path) -> None:
    """What check-config must foresee: the start refuses the file, exit code 2."""
    out = run_cli("run", "-c", str(_config(tmp_path)))
    assert out.returncode == 2, out
    assert "no entity in it" in out.stderr, out.stderr


@pytest.mark.xfail(
    strict=True,
    reason="attack 18: check-config says 'config OK' of a cty file with no entity, which the "
    "start refuses (exit code 2)",
)
def test_check_config_refuses_a_cty_file_without_entities(tmp_path: Path) -> None:
    out = cli("check-config", "-c", str(_config(tmp_path)))
    assert "config OK" not in out.stdout, out.stdout
    assert out.returncode == 2, out
    assert "cty_file" in out.stderr, out.stderr
