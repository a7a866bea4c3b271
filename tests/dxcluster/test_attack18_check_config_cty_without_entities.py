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


def test_check_config_refuses_a_cty_file_without_entities(tmp_path: Path) -> None:
    out = cli("check-config", "-c", str(_config(tmp_path)))
    assert "config OK" not in out.stdout, out.stdout
    assert out.returncode == 2, out
    assert "cty_file" in out.stderr, out.stderr


@pytest.mark.parametrize(
    ("cty_file", "says"),
    [
        ("/dev/zero", "/dev/zero cannot be read: it is no regular file"),  # (read 1 byte: "OK")
        ("nowhere.dat", "nowhere.dat cannot be read: No such file or directory"),
    ],
)
def test_check_config_judges_the_cty_file_in_the_start_s_words(
    tmp_path: Path, cty_file: str, says: str
) -> None:
    """One reading for both (interfaces/dxcluster/setup.py read_cty): check-config names the
    key and says what the start would."""
    config = _config(tmp_path)
    path = cty_file if cty_file.startswith("/") else str(tmp_path / cty_file)
    config.write_text(config.read_text().replace(str(tmp_path / "cty.dat"), path))
    out = cli("check-config", "-c", str(config))
    assert out.returncode == 2 and "config OK" not in out.stdout, out
    assert f"dxcluster.cty_file {path}" in out.stderr and says in out.stderr, out.stderr
