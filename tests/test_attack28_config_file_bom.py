"""Attack 28: a configuration file saved with a UTF-8 byte-order mark (Windows Notepad before
2019, PowerShell 5's ``Set-Content -Encoding UTF8``; the remote's file is edited on Windows,
docs/remote.md) stops the start with ``config file ... is not valid TOML: Invalid statement (at
line 1, column 1)``: the user opens line 1 in the editor, sees ``[mqtt]`` or a comment, and
nothing wrong with it (the mark is invisible there). The bridge drops a byte-order mark before
every MQTT payload's words (docs/mqtt.md); a file with one should be read as well, or the
error should say what is at column 1."""

from __future__ import annotations

from pathlib import Path

from bridge.settings import ConfigError, load_settings

BOM = b"\xef\xbb\xbf"


def test_a_config_files_byte_order_mark_is_read_or_named(tmp_path: Path) -> None:
    cfg = tmp_path / "bridge.toml"
    cfg.write_bytes(
        BOM
        + (
            f'state_file = "{tmp_path / "state.json"}"\n'
            '[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "/dev/null"\n'
        ).encode()
    )
    try:
        settings = load_settings(cfg, environ={})
    except ConfigError as exc:
        said = str(exc).lower()
        assert "byte-order mark" in said or "bom" in said or "u+feff" in said, exc
        return
    assert [r.id for r in settings.rotators] == ["tower"]
