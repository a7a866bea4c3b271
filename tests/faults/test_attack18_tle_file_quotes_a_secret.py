"""Attack 18: ``tracking.tle_file`` naming a secret's file (the MQTT password file beside it in
/etc/rotor-bridge, a slip of tab completion) passes check-config, and the start's catalog
reading quotes that file's first line in its warning: the MQTT password, in the log (the
journal) at WARNING. The settings know the file is the password's (``mqtt.password_file``,
settings/config.py rule 6 lists the files read), and every other message names a secret's
file without quoting it (settings/files.py rule 3)."""

from __future__ import annotations

import os
from pathlib import Path

from tests.support import BridgeProcess, wait_until
from tests.support.mosquitto import Mosquitto

SECRET = "Wr1tten-0nly-1n-the-password-file"


def test_a_tle_file_that_is_the_password_file_never_puts_the_password_in_the_log(
    tmp_path: Path, broker: Mosquitto
) -> None:
    secret_file = tmp_path / "mqtt-password"
    secret_file.write_text(SECRET + "\n")
    os.chmod(secret_file, 0o600)
    bridge = BridgeProcess(
        tmp_path,
        {
            "state_file": str(tmp_path / "state.json"),
            "mqtt": {
                "host": "127.0.0.1",
                "port": broker.port,
                "username": "rotor",
                "password_file": str(secret_file),
            },
            "station": {"locator": "JO62qm"},
            "tracking": {"tle_file": str(secret_file)},
            "rotators": [{"id": "sat", "model": "rot2prog", "port": str(tmp_path / "tty")}],
        },
        log_level="DEBUG",
    ).start()
    try:  # refused as a configuration error, or running with its catalog read
        wait_until(
            lambda: not bridge.alive() or "satellite(s)" in bridge.log(),
            what="the start to end or to read the TLE file",
        )
    finally:
        if bridge.alive():
            bridge.terminate()
    assert SECRET not in bridge.log()
