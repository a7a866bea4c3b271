"""Review 76, at the root: a home folder whose name is not UTF-8 (settings/base.py rule 3: it may
be any bytes) holds the rotator's serial port (not there), its pty's link, the state file and
the audit file, each written ``~/...``. Whatever the bridge says of them, it says in UTF-8
(core/text.py ``shown_path``): every payload it puts on the broker, retained or not, Home
Assistant's discovery too, is UTF-8 and, where JSON, holds no lone surrogate (``\\udce9``, which
a strict parser, Home Assistant's, refuses), and so is every line it logs. The review found one
place at a time (R/error, the pty's claim, the settings' refusals); this catches the next."""

from __future__ import annotations

import json
import logging
import time
from pathlib import Path
from typing import Any

import pytest

from tests.support.mqtt import Message
from tests.support.rig import Rig


def _texts(doc: Any) -> list[str]:
    """Every text of a JSON document, its keys too."""
    if isinstance(doc, str):
        return [doc]
    if isinstance(doc, dict):
        return [t for k, v in doc.items() for t in [k, *_texts(v)]]
    if isinstance(doc, list):
        return [t for v in doc for t in _texts(v)]
    return []


def _not_utf8(payload: bytes) -> str | None:
    """Why ``payload`` is no strict UTF-8 text (a JSON document's texts each UTF-8), or None."""
    try:
        text = payload.decode("utf-8")  # strict
    except UnicodeDecodeError as exc:
        return f"not UTF-8: {exc}"
    try:
        doc = json.loads(text)
    except ValueError:
        return None  # no JSON: a bearing, "online"
    for t in _texts(doc):
        try:
            t.encode("utf-8")
        except UnicodeEncodeError:
            return f"a lone surrogate in the JSON text {t!r}"
    return None


def test_what_a_bridge_in_a_home_folder_not_in_utf8_says_is_utf8(
    rig: Rig, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    home = tmp_path / "h\udce9"  # b"h\xe9": a Latin-1 name, as os.environ holds it
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    caplog.set_level(logging.DEBUG)
    rig.sections = {"state_file": "~/state.json", "audit_file": "~/audit.jsonl"}
    rig.add("tower", gs232_pty="~/gs232")
    rig.rotators[0]["port"] = "~/rotor"  # not there: the bridge says so, and keeps trying
    t = time.monotonic()
    rig.start()

    def missing(m: Message) -> bool:
        said = json.loads(m.payload).get("last_error") or ""
        return "rotor does not exist" in said

    rig.probe.wait_for(rig.t("status"), missing, after=t)  # its word on the port, retained
    assert (home / "gs232").is_symlink() and (home / "state.json").exists()
    ours = (f"{rig.base}/", "homeassistant/")
    heard = [(m.topic, m.payload) for m in rig.probe.messages if m.topic.startswith(ours)]
    retained = rig.retained()
    assert any("last_error" in p.decode() for p in retained.values())  # (what it looks at)
    faults = [
        (topic, why, payload[:300])
        for topic, payload in [*retained.items(), *heard]
        if (why := _not_utf8(payload)) is not None
    ]
    assert not faults, faults
    logged = [r.getMessage() for r in caplog.records]
    assert any("h\\udce9" in line for line in logged)  # (it names the home folder's paths)
    unsaid = [line for line in logged if not _utf8(line)]
    assert not unsaid, [ascii(line) for line in unsaid]


def _utf8(line: str) -> bool:
    try:
        line.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True
