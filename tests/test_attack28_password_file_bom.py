"""Attack 28: a password file saved with a UTF-8 byte-order mark (Windows PowerShell 5's
``Set-Content -Encoding UTF8`` / ``Out-File -Encoding utf8``, older Notepad; the remote runs on
Windows, docs/remote.md) is taken with the mark as the password's first character. The
broker refuses that login ("check mqtt.username and mqtt.password"), and the console's login
says "wrong password" to the right one (nobody can type U+FEFF), while the file shows the right
password in every editor and ``check-config`` says "config OK".

Every MQTT payload drops a leading byte-order mark as no part of the words (docs/mqtt.md); a
password file should do the same, or refuse the mark naming the key. Either passes here."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.settings import ConfigError, load_settings

BOM = b"\xef\xbb\xbf"


def _config(tmp_path: Path, table: str, secret: Path) -> Path:
    cfg = tmp_path / "bridge.toml"
    login = 'username = "rotor"\n' if table == "mqtt" else ""
    cfg.write_text(
        f'state_file = "{tmp_path / "state.json"}"\n'
        f'[{table}]\n{login}password_file = "{secret}"\n'
        '[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "/dev/null"\n'
    )
    return cfg


@pytest.mark.parametrize("table", ["mqtt", "web"])
def test_a_password_files_byte_order_mark_is_no_part_of_the_password(
    tmp_path: Path, table: str
) -> None:
    secret = tmp_path / f"{table}-password"
    secret.write_bytes(BOM + b"s3cret-pass\r\n")
    secret.chmod(0o600)
    try:
        settings = load_settings(_config(tmp_path, table, secret), environ={})
    except ConfigError as exc:  # refused, naming the key: as good
        assert f"{table}.password_file" in str(exc) or "password_file" in str(exc), exc
        return
    password = settings.mqtt.password if table == "mqtt" else settings.web.password
    assert password is not None
    assert password.get_secret_value() == "s3cret-pass"
