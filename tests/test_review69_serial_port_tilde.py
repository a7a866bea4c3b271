"""Review 69: settings/base.py rule 7 says a path beginning with ``~`` is the home folder's "for
every key that takes a path", but a rotator's serial port is a text key (``port: str``), so
``port = "~/rotor"`` (a socat or udev link kept in the service user's home) is opened as
``./~/rotor`` of the working directory. check-config says the port it can see is NOT FOUND
and warns that the bridge will keep trying to open it, which is what ``run`` then does, for
ever. The pty keys (``gs232_pty``...) are expanded (interfaces/ptylines.py); the serial port,
the one path every configuration has, is not."""

from __future__ import annotations

import os
from pathlib import Path

from tests.support import cli, to_toml


def test_a_serial_port_written_with_a_tilde_is_the_one_in_the_home_folder(tmp_path: Path) -> None:
    home = tmp_path / "home"
    home.mkdir()
    controller, line = os.openpty()  # a real pseudo-terminal: the serial line
    try:
        (home / "rotor").symlink_to(os.ttyname(line))
        config = tmp_path / "bridge.toml"
        config.write_text(
            to_toml(
                {
                    "state_file": tmp_path / "state.json",
                    "mqtt": {"host": "127.0.0.1"},
                    "rotators": [{"id": "tower", "model": "rotorez", "port": "~/rotor"}],
                }
            )
        )
        out = cli("check-config", "-c", str(config), env={"HOME": str(home)})
    finally:
        os.close(controller)
        os.close(line)
    assert out.returncode == 0, out.stderr
    assert "NOT FOUND" not in out.stdout, out.stdout
    assert "does not exist now" not in out.stdout + out.stderr, out.stdout + out.stderr
