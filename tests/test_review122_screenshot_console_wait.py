"""Review 122: ``scripts/screenshot console`` (docs/node-red.md: the README's pictures are remade
with it) waits for the bridge's console to come up with ``answers`` on the console's HTTP port.
Since "demo: a broker answers when a CONNECT gets a CONNACK", ``answers`` sends an MQTT CONNECT
and wants a CONNACK, which a web server never sends: the script waits its 20 s and ends with
"screenshot: the console did not answer" (exit 1) although the console is up, and
docs/images/console.png can no longer be remade. The commit moved the tests' and web proxies'
TCP looks to ``listens`` and missed this one.

A real bridge with its console, a real mosquitto and an emulated Rotor-EZ (the script's own
``running_bridge``); only the browser is replaced, by a stand-in that notes it was reached."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "screenshot.py"


def _script(monkeypatch: pytest.MonkeyPatch) -> ModuleType:
    spec = importlib.util.spec_from_file_location("review122_screenshot", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, module)
    spec.loader.exec_module(module)
    return module


class BrowserReached(Exception):
    """The script found the console up and went on to open the browser."""


def test_the_screenshot_script_finds_the_bridges_console_up(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    script = _script(monkeypatch)  # imports playwright, as the script does

    def browser(*_: Any, **__: Any) -> Any:
        raise BrowserReached

    monkeypatch.setattr(script, "sync_playwright", browser)
    try:
        code = script.shoot_console(tmp_path, tmp_path / "console.png", "/usr/bin/chromium")
    except BrowserReached:
        return
    said = capsys.readouterr().err
    pytest.fail(f"the script never opened the browser (exit {code}): {said}")
