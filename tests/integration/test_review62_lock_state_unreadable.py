"""Review 62 of kept.py rule 10 (attack 15): a start whose state file does not say the lock ON
takes the lock from the broker's retained ``R/lock/state``. A broker that lets the bridge
publish that topic but not read it (an ACL that grants its states ``write`` alone, as review
35's administrator did for the markers) never hands the ON on: the look ends as if the broker
held nothing, the rotator starts unlocked, the bridge puts OFF over the ON, and nothing says
the lock could not be read."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bridge.runtime.state_store import StateStore
from tests.support.rig import Rig


@pytest.fixture
def broker_conf(tmp_path: Path) -> str:
    acl = tmp_path / "acl"
    acl.write_text(
        "topic readwrite #\n"  # anonymous: the probe, the stranger
        "user bridge\n"
        "topic write #\n"
        "topic read rotor/+\n"  # the rotator's commands (its topic is "rotor")
        "topic read rotor/bridge/#\n"
        "topic read rotor/option/#\n"
        "topic read homeassistant/#\n"
    )
    # (started as root, mosquitto would become user "mosquitto", who cannot read pytest's tmp)
    return f"allow_anonymous true\nacl_file {acl}\nuser root"


def test_a_lock_on_the_bridge_cannot_read_is_not_dropped_in_silence(rig: Rig) -> None:
    rig.mqtt_extra = {"username": "bridge", "password": "anything"}
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    assert StateStore(rig.settings.state_file).set_locked("tower", False)
    probe = rig.probe
    probe.publish("rotor/lock/state", "ON", retain=True)  # locked for tower work
    after = probe.caught_up()
    rig.start()
    rig.ready("tower", after=after)
    probe.publish("rotor/target", "200")
    done = probe.wait_for(
        "rotor/audit", lambda m: json.loads(m.text)["command"] == "target '200'", after=after
    )
    refused = json.loads(done.text)["result"].startswith("refused")
    said = [
        m
        for m in probe.on("rotor/error")
        if m.t >= after and json.loads(m.text)["kind"] == "state" and "lock" in m.text
    ]
    assert refused or said, (
        f"lock/state {probe.last('rotor/lock/state')}, target {done.text}, "
        f"rotor at {emu.state().az_deg:.0f}: the broker's lock ON dropped without a word"
    )
