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
from typing import Any

import pytest

from bridge.settings import settings_from
from bridge.settings.mqtt import MqttSettings
from tests.faults.conftest import Pki
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


@pytest.mark.parametrize(
    ("keys", "said"),
    [
        ({"mqtt": {"username": "u", "password_file": "~/pw"}}, "password_file {home}/pw: No such"),
        ({"mqtt": {"tls": {"enabled": True, "ca_file": "~/ca.pem"}}}, "ca_file {home}/ca.pem is"),
        ({"audit_file": "~"}, "audit_file: {home} is a folder: name a file in it ({home}/audit"),
    ],
    ids=["mqtt.password_file", "mqtt.tls.ca_file", "audit_file"],
)
def test_a_refusal_names_a_file_in_a_home_folder_not_in_utf8_escaped(
    tmp_path: Path, keys: dict[str, Any], said: str
) -> None:
    """settings/base.py rule 8: the refusal naming the file was a UnicodeEncodeError traceback
    in pydantic, exit 1 (which the systemd unit restarts for ever), for check-config and run."""
    home = tmp_path / "h\udce9"
    home.mkdir()
    base = {
        "mqtt": {"host": "127.0.0.1"},
        "rotators": [{"id": "tower", "model": "rotorez", "port": "/dev/rotor"}],
    }
    config = tmp_path / "bridge.toml"
    config.write_text(to_toml(base | keys | {"mqtt": base["mqtt"] | keys.get("mqtt", {})}))
    out = run_cli("check-config", "-c", str(config), env={"HOME": str(home)})
    assert "Traceback" not in out.stderr, out.stderr
    assert out.returncode == 2, out.stderr
    shown = str(home).encode("utf-8", "backslashreplace").decode()  # .../h\udce9
    assert said.format(home=shown) in out.stderr, out.stderr


def test_a_serial_port_and_a_pty_in_a_home_folder_not_in_utf8_are_taken_and_shown(
    tmp_path: Path,
) -> None:
    """Rule 3 exempts the home folder: a port '~/rotor' was refused there as holding "U+DCE9, a
    control character" (rule 6 judged it once expanded), a pty '~/...' by pydantic's
    min_length ("unable to parse raw data as a unicode string")."""
    home = tmp_path / "h\udce9"
    home.mkdir()
    (home / "rotor").touch()
    rotator = {"id": "tower", "model": "rotorez", "port": "~/rotor", "gs232_pty": "~/gs232"}
    config = tmp_path / "bridge.toml"
    config.write_text(to_toml({"mqtt": {"host": "127.0.0.1"}, "rotators": [rotator]}))
    out = run_cli("check-config", "-c", str(config), env={"HOME": str(home)})
    assert out.returncode == 0, out.stderr
    shown = str(home).encode("utf-8", "backslashreplace").decode()
    assert f"tower: Rotor-EZ (rotorez) on {shown}/rotor (found)" in out.stdout, out.stdout
    assert f"GS-232B on a pty at {shown}/gs232" in out.stdout, out.stdout


def test_settings_with_paths_in_a_home_folder_not_in_utf8_load_as_they_are_printed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """What check-config --full prints loads back (test_composite_settings.py's promise), and
    the stop express, which is handed the broker's settings so and reads them again
    (interfaces/mqtt/express.py), reads them: a TLS file '~/...' there was refused as not
    UTF-8 (rule 3), and the express never started."""
    home = tmp_path / "h\udce9"
    Pki(home / "pki")
    monkeypatch.setenv("HOME", str(home))
    tls = {"enabled": True, "ca_file": "~/pki/ca.crt"}
    rotator = {"id": "tower", "model": "rotorez", "port": "~/rotor", "dcu1_pty": "~/dcu1"}
    s = settings_from({"mqtt": {"host": "h", "tls": tls}, "rotators": [rotator]}, environ={})
    assert s.mqtt.tls.ca_file == home / "pki" / "ca.crt"
    again = MqttSettings.model_validate(s.mqtt.model_dump(mode="json"))  # the express's
    assert again.tls.ca_file == s.mqtt.tls.ca_file
    r = s.rotators[0]
    assert (r.port, r.dcu1_pty) == (str(home / "rotor"), str(home / "dcu1"))
    back = type(r).model_validate(r.model_dump())
    assert (back.port, back.dcu1_pty) == (r.port, r.dcu1_pty)
