"""Review 69: settings/base.py rule 3 refuses a path that is not UTF-8 text, since the bridge
names its paths in what it prints; "the home folder" is exempt, as it "may be any bytes". Rule
7 (9820130f) now puts the home folder into any key written ``~/...``, and check-config prints
those paths (the summary's "state file: ...") with ``print``: under a UTF-8 locale other than
C.UTF-8 (en_US.UTF-8, de_DE.UTF-8: what a desktop or a server's locale.conf sets) Python's
stdout refuses the lone surrogate a non-UTF-8 byte of the home folder's name is, and
check-config ends in a UnicodeEncodeError traceback, exit 1, instead of its report. (The
default state file, in the home folder too, did so before rule 7; its test loads the settings
and prints nothing.)"""

from __future__ import annotations

from pathlib import Path

from tests.support import run_cli, to_toml


def test_check_config_reports_a_tilde_path_in_a_home_folder_not_in_utf8(tmp_path: Path) -> None:
    home = tmp_path / "h\udce9"  # b"h\xe9": a Latin-1 name, as os.environ holds it
    home.mkdir()
    config = tmp_path / "bridge.toml"
    config.write_text(
        to_toml(
            {
                "state_file": "~/rb/state.json",
                "mqtt": {"host": "127.0.0.1"},
                "rotators": [{"id": "tower", "model": "rotorez", "port": "/dev/rotor"}],
            }
        )
    )
    # PYTHONIOENCODING=utf-8: stdout as under en_US.UTF-8 (strict), C.UTF-8 being lenient
    out = run_cli(
        "check-config", "-c", str(config), env={"HOME": str(home), "PYTHONIOENCODING": "utf-8"}
    )
    assert "Traceback" not in out.stderr, out.stderr
    assert out.returncode == 0, out.stderr
    assert "config OK" in out.stdout, out.stdout


def test_check_config_names_a_configuration_file_whose_path_is_not_utf8_escaped(
    tmp_path: Path,
) -> None:
    """The file's own path may be any bytes too (settings/base.py rule 3): its last line named
    it with ``print`` and ended in the same traceback; it reads as the log would write it."""
    folder = tmp_path / "h\udce9"
    folder.mkdir()
    config = folder / "bridge.toml"
    config.write_text(
        to_toml(
            {
                "mqtt": {"host": "127.0.0.1"},
                "rotators": [{"id": "tower", "model": "rotorez", "port": "/dev/rotor"}],
            }
        )
    )
    out = run_cli("check-config", "-c", str(config), env={"PYTHONIOENCODING": "utf-8"})
    assert "Traceback" not in out.stderr, out.stderr
    assert out.returncode == 0, out.stderr
    shown = str(config).encode("utf-8", "backslashreplace").decode()  # .../h\udce9/bridge.toml
    assert out.stdout.splitlines()[-1] == f"config OK: {shown}", out.stdout
