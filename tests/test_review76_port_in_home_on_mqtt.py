"""Review 76 of b9e5cc7d (settings/base.py rules 3 and 7, ``beyond_home``): a serial port
written ``~/...`` in a home folder whose name is not UTF-8 is now taken. Rule 3 refused it
because "the bridge names its paths in its messages and on MQTT, and takes none that is not"
UTF-8: the bridge's word on the port (R/error, R/status's last_error: "... does not exist",
"serial link to ... lost", "controller on ... does not answer") now carries the home folder's
byte as a lone surrogate, JSON's ``\\udce9``, which no UTF-8 holds and a strict parser (Home
Assistant's orjson, serde_json) refuses: the rule-3 fault its test names for a rotator's name
(a JSON parser refusing its discovery). Rule 8's ``shown_path`` escapes a refusal's path, not
what the running bridge says of the port."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import pytest

from bridge.core.text import bad_char
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


def test_what_the_bridge_says_of_a_port_in_a_home_folder_not_in_utf8_is_utf8_text(
    rig: Rig, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    home = tmp_path / "h\udce9"  # b"h\xe9": a Latin-1 name, as os.environ holds it
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    rig.add("tower")
    rig.rotators[0]["port"] = "~/rotor"  # not there (yet): the bridge says so, and keeps trying
    t = time.monotonic()
    rig.start()
    said = rig.probe.wait_for(
        rig.t("error"), lambda m: json.loads(m.payload)["kind"] == "serial", after=t
    )
    doc = json.loads(said.payload)
    assert "rotor does not exist" in doc["message"], doc
    assert all(bad_char(text) is None for text in _texts(doc)), said.payload
