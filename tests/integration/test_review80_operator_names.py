"""Review 80: a sender's own name whose first word spells an interface is refused, though the
bridge never names anyone so.

b1da53ed made core/model.py ``operator_name`` (valid_operator, and not ``interface_name``) the
one test of the name a sender gives itself: the MQTT user property ``operator``, a release's
payload, the remote's configured operator. ``interface_name`` refuses any text whose *first
word* is a Source value, casefolded. But the bridge names a sender without a name only as
``<interface>`` alone (``mqtt``) or ``<interface> <peer address>`` (``rotctld 192.168.1.20``,
``n1mm 192.168.1.7``: every network interface has its peer): ``N1MM`` -- a real call sign, the
author of N1MM Logger+ -- and ``Mqtt Guy`` are no name the bridge gives. Before b1da53ed both
were audited, and shown as R/status ``last_operator``, as themselves; now every command they
send goes as plain ``mqtt`` (logged "operator ignored") and a remote configured with such an
operator does not start at all.

Real mosquitto, the Rotor-EZ emulator on a pty through pyserial, the App in-process (the
audit file as test_attack25_operator_named_as_an_interface reads it)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bridge.remote.settings import load_remote_settings
from tests.integration.test_attack25_operator_named_as_an_interface import audited_target
from tests.support.rig import Rig

NAMES = ["N1MM", "Mqtt Guy"]  # a real call sign; a name (no interface's peer is a word)
REFUSED = "review 80: a name whose first word is an interface's is refused as an operator's"


@pytest.mark.parametrize("name", NAMES)
def test_a_call_sign_spelled_like_an_interface_is_audited_as_sent(rig: Rig, name: str) -> None:
    line = audited_target(rig, "op", name)
    assert line["operator"] == name, f"{name!r} sent target 40; the audit line says {line}"


@pytest.mark.parametrize("name", NAMES)
def test_a_remote_whose_operator_is_spelled_like_an_interface_starts(
    tmp_path: Path, name: str
) -> None:
    path = tmp_path / "remote.toml"
    path.write_text(
        f'operator = {json.dumps(name)}\n[mqtt]\nhost = "station.example.org"\n'
        "[[endpoints]]\nrotctld_port = 4533\n"
    )
    assert load_remote_settings(str(path)).operator == name  # type: ignore[attr-defined]
