"""M2 RC2800 end to end: real mosquitto, real pyserial on a pty, the bridge, and the RC2800
emulator (written from the documents and judged by Hamlib's rotctl -m 1001) as the controller,
plain, echoing its commands, and streaming its position unasked. The 200 ms between the axes
is proven in virtual time (tests/engine/test_session_rc2800.py): on a busy machine a pty hands
the emulator two frames late together, so its count here would measure the machine."""

from __future__ import annotations

import json
import time
from typing import Any

import pytest

from tests.support.mqtt import Message
from tests.support.rig import Rig
from tests.support.waiting import slow

KINDS = [{}, {"echo": True, "stream_s": 0.25}]  # a plain box; one that echoes and streams


def not_junk(message: Message) -> bool:
    """An error that is not a line the power cycle cut short, told as junk (what it is)."""
    return bool(json.loads(message.payload)["kind"] != "protocol")


def status(rig: Rig) -> dict[str, object]:
    return dict(json.loads(rig.retained()["rotor/status"]))


@pytest.mark.parametrize("kind", KINDS, ids=["plain", "echo+stream"])
def test_az_el_target_bearing_and_stop(rig: Rig, kind: dict[str, Any]) -> None:
    emu = rig.add("sat", model="rc2800", emu={"start_az_deg": 10.3, "start_el_deg": 5, **kind})
    rig.start()
    rig.ready("sat", timeout_s=15)
    snap = rig.retained()
    assert snap["rotor/bearing"] == b"10.3" and snap["rotor/elevation"] == b"5"

    t = time.monotonic()  # before the move: its idle may come before the emulator is asked
    rig.probe.publish("rotor/target", '{"azimuth": 123.4, "elevation": 45}')
    emu.wait_for(lambda s: (s.az_deg, s.el_deg) == (123.4, 45.0) and not s.is_moving, 20)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    assert (status(rig)["bearing"], status(rig)["elevation"]) == (123.4, 45.0)
    assert sorted(f.data for f in emu.frames("move")) == [b"A123.4", b"E45.0"]

    rig.probe.publish("rotor/target", '{"azimuth": 300, "elevation": 10}')
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 140, 10)
    t = time.monotonic()
    rig.probe.publish("rotor/stop", "STOP")
    stopped = emu.wait_for(lambda s: not s.is_moving, 5)
    log = emu.log()  # the STOP may come twice (lane and main connection): S to each axis
    stops = [(log[i - 1].data, f.data) for i, f in enumerate(log) if f.outcome == "stop"]
    assert stopped.az_deg < 290 and set(stops) == {(b"A", b"S"), (b"E", b"S")}, stops
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    doc = status(rig)
    assert (doc["bearing"], doc["elevation"]) == (
        round(emu.state().az_deg, 1),
        round(emu.state().el_deg or 0.0, 1),
    )  # where it stopped, read back
    assert emu.frames("refused") == []


def test_a_new_bearing_while_turning_goes_straight_out(rig: Rig) -> None:
    emu = rig.add("sat", model="rc2800", emu={"start_az_deg": 0, "start_el_deg": 0})
    rig.start()
    rig.ready("sat", timeout_s=15)
    rig.probe.publish("rotor/target", "200 40")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 40, 10)
    rig.probe.publish("rotor/target", "20.5 10")  # no stop first
    emu.wait_for(lambda s: (s.az_deg, s.el_deg) == (20.5, 10.0) and not s.is_moving, 20)
    moves = [f.data for f in emu.frames("move")]
    assert sorted(moves[:2]) == [b"A200.0", b"E40.0"] and sorted(moves[2:]) == [b"A20.5", b"E10.0"]
    assert emu.frames("stop") == []


@pytest.mark.parametrize("kind", KINDS, ids=["plain", "echo+stream"])
def test_junk_gives_an_error_and_changes_nothing(rig: Rig, kind: dict[str, Any]) -> None:
    emu = rig.add("sat", model="rc2800", emu={"start_az_deg": 77.7, "start_el_deg": 7, **kind})
    rig.start()
    rig.ready("sat", timeout_s=15)
    junk = (b"garbage\r", b"A P= 3\xff3.0 S=9 MV\r", b"A P= 999.0 S=9 MV\r", b"E P=  1")
    rig.junk_reported("sat", *junk)
    assert {m.text for m in rig.probe.on("rotor/bearing")} == {"77.7"}
    assert {m.text for m in rig.probe.on("rotor/elevation")} == {"7"}
    assert emu.frames("move") == [] and emu.state().az_deg == 77.7


@pytest.mark.parametrize("model", ["rc2800", "rc2800-az"])
def test_a_box_power_cycled_mid_turn_is_said_to_have_stopped_short_not_stalled(
    rig: Rig, model: str
) -> None:
    """The box forgets its turn at a power cycle and says its motors are stopped (``ST``): the
    turn is said dropped, no stall (observed: 'rotor stalled at 80.2° ... brake paddle
    pressed', and rotor health counted a stall), and nothing turns the rotor on."""
    # (a power cycle cuts the poll under way and its reply: on a loaded host the rig's 1 s
    # silence left the answers after it 1.4 s late, and the bridge took the line for garbled
    # and dropped the turn itself before the box's own word could: a CI run)
    roomy = {"silence_timeout_s": slow(3.0), "stall_timeout_s": slow(6.0)}
    emu = rig.add("sat", model=model, emu={"start_az_deg": 10}, **roomy)
    rig.start()
    rig.ready("sat", timeout_s=15)
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 60, 10)
    t = time.monotonic()
    emu.power_cycle()
    at = emu.state().az_deg
    err = json.loads(rig.probe.wait_for("rotor/error", not_junk, after=t).payload)
    assert err["kind"] == "stalled", err
    assert err["message"].startswith("the controller stopped turning short of its target at ")
    assert err["message"].endswith(
        "its turn to 300° was dropped, not resumed: send the target again"
    )
    said = rig.probe.wait_for("rotor/status", lambda m: b"stopped turning short" in m.payload)
    doc = json.loads(said.payload)
    assert doc["last_error"] == err["message"] and doc["target"] is None
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    health = status(rig)["health"]
    assert isinstance(health, dict) and health["stalls"] == 0  # observed: 1
    assert emu.state().az_deg == at and not emu.state().is_moving  # not turned on
