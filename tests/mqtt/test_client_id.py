"""The default MQTT client id: one per installation, the same across restarts, at most 23
characters (what every MQTT 3.1.1 broker must accept). Two installations on one host (the demo
beside the real one, a second config) must not take each other's session over."""

from __future__ import annotations

import json
import re
import socket
from pathlib import Path

import pytest

from bridge.settings import load_settings
from bridge.settings.report import masked
from tests.support import cli

CONFIG = """
state_file = "{state}"
[mqtt]
base_topic = "{base}"
{extra}
[[rotators]]
id = "tower"
model = "rotorez"
port = "/dev/ttyUSB0"
"""


def config(tmp_path: Path, name: str, state: str, base: str = "rotor", extra: str = "") -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(CONFIG.format(state=tmp_path / state, base=base, extra=extra))
    return path


def client_id(path: Path) -> str:
    return str(masked(load_settings(path))["mqtt"]["client_id"])


def shown_by_check_config(path: Path) -> str:
    done = cli("check-config", "--full", "-c", str(path))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()  # every value: the JSON between the summary and "config OK"
    full = lines[lines.index("{") : lines.index("}") + 1]
    return str(json.loads("\n".join(full))["mqtt"]["client_id"])


def test_one_installation_keeps_its_id_across_restarts(tmp_path: Path) -> None:
    path = config(tmp_path, "tower", "state.json")
    first, second = shown_by_check_config(path), shown_by_check_config(path)  # two processes
    assert first == second == client_id(path)
    assert len(first) <= 23 and re.fullmatch(r"rotor-[a-z0-9-]+", first), first
    host = re.sub(r"[^a-z0-9-]", "", socket.gethostname().split(".")[0].lower())[:10]
    assert host.strip("-") in first  # the broker's log says which host it is


def test_two_installations_on_one_host_get_different_ids(tmp_path: Path) -> None:
    real = client_id(config(tmp_path, "real", "real/state.json"))
    other_state = client_id(config(tmp_path, "demo", "demo/state.json"))
    other_topic = client_id(config(tmp_path, "lab", "real/state.json", base="lab/rotor"))
    assert len({real, other_state, other_topic}) == 3


def test_an_explicit_client_id_is_used_as_given(tmp_path: Path) -> None:
    path = config(tmp_path, "x", "state.json", extra='client_id = "tower-bridge-with-a-long-name"')
    assert client_id(path) == "tower-bridge-with-a-long-name"


@pytest.mark.parametrize(
    "host", ["raspberrypi-shack-tower-2.home.example.org", "shack", "日本語", "-", "a" * 64]
)
def test_any_host_name_gives_a_short_plain_id(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, host: str
) -> None:
    path = config(tmp_path, "tower", "state.json")
    monkeypatch.setattr(socket, "gethostname", lambda: host)
    cid = client_id(path)
    assert len(cid) <= 23 and re.fullmatch(r"rotor-([a-z0-9][a-z0-9-]*-)?[0-9a-f]{6}", cid), cid
    monkeypatch.setattr(socket, "gethostname", lambda: host + "x")
    assert client_id(path) != cid  # the full name counts, not only the part shown
