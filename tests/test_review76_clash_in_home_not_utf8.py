"""Review 76 of c6ac9e56 (settings/base.py rule 8: "a refusal names a path as ``shown_path``
spells it"): two refusals naming a path were left out, settings/config.py's rule 6 (a file
the bridge writes that is also another key's file) and rule 7 (``secret_read``: a file read
as no secret that holds one). In a home folder whose name is not UTF-8 a file there written
``~/...`` ends check-config and run in the UnicodeEncodeError traceback inside pydantic that
rule 8 says it fixed, exit 1 (which the systemd unit restarts for ever), not the one-line error
and exit 2."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest

from tests.support import run_cli, to_toml


@pytest.mark.parametrize(
    ("keys", "said"),
    [
        (
            {"state_file": "~/rb.json", "audit_file": "~/rb.json"},
            "state_file {home}/rb.json is also audit_file: the bridge writes there",
        ),
        (
            {
                "mqtt": {"username": "u", "password_file": "~/pw"},
                "tracking": {"tle_file": "~/pw"},
            },
            "tracking.tle_file {home}/pw is also mqtt.password_file: a secret's file",
        ),
    ],
    ids=["written-twice", "secret-read"],
)
def test_a_clash_of_files_in_a_home_folder_not_in_utf8_is_one_line_and_exit_2(
    tmp_path: Path, keys: dict[str, Any], said: str
) -> None:
    home = tmp_path / "h\udce9"  # b"h\xe9": a Latin-1 name, as os.environ holds it
    home.mkdir()
    (home / "pw").write_text("s3cret\n")
    os.chmod(home / "pw", 0o600)
    mqtt = {"host": "127.0.0.1", **keys.get("mqtt", {})}
    doc = {
        **keys,
        "mqtt": mqtt,
        "rotators": [{"id": "tower", "model": "rotorez", "port": "/dev/rotor"}],
    }
    config = tmp_path / "bridge.toml"
    config.write_text(to_toml(doc))
    for command in ("check-config", "run"):
        out = run_cli(command, "-c", str(config), env={"HOME": str(home)})
        assert "Traceback" not in out.stderr, out.stderr[-600:]
        assert out.returncode == 2, out.stderr
        shown = str(home).encode("utf-8", "backslashreplace").decode()  # .../h\udce9
        assert said.format(home=shown) in out.stderr, out.stderr
        assert "s3cret" not in out.stderr + out.stdout
