"""Rotor health end to end: real mosquitto, the Rotor-EZ emulator on a real pty, the bridge.

What a user sees: ``R/health`` reports the speeds the rotor really turns at (the emulator's
physics, which the bridge never sees), keeps what it learned across a restart of the bridge
(the state file), and Home Assistant's sensors carry the numbers with a ``state_class`` for
its long-term statistics.
"""

from __future__ import annotations

import json
import time

import pytest

from tests.support import retained_snapshot
from tests.support.rig import Rig
from tests.test_homeassistant import render

PREFIX = "homeassistant"


def _true_speed(rig: Rig) -> float:
    """The emulated rotor's real speed: its physics axis's (emulators/physics.py)."""
    return float(rig.emu.call(lambda device, _now: device._axis.speed_deg_s))


def _move(rig: Rig, az_deg: int, moves: int) -> dict:
    """Turn to ``az_deg``; R/health once it has counted the move."""
    t0 = time.monotonic()
    rig.probe.publish(rig.t("target"), str(az_deg))
    msg = rig.probe.wait_for(
        rig.t("health"), lambda m: json.loads(m.payload)["moves"] >= moves, 30, after=t0
    )
    return json.loads(msg.payload)


def test_health_reports_real_speeds_keeps_them_across_a_restart_and_feeds_ha(rig: Rig) -> None:
    rig.add("tower", emu={"start_az_deg": 20})
    rig.start()
    rig.ready("tower")
    speed = _true_speed(rig)
    for n in range(1, 7):  # three moves each way: the recent median needs three
        health = _move(rig, 200 if n % 2 else 20, n)
    assert health["speed_cw_deg_s"] == pytest.approx(speed, rel=0.1)
    assert health["speed_ccw_deg_s"] == pytest.approx(speed, rel=0.1)
    assert health["moves"] == 6 and health["stalls"] == 0 and health["warnings"] == []
    assert health["odometer_deg"] == pytest.approx(6 * 180, rel=0.05)
    assert health["start_delay_s"] is not None and health["start_delay_s"] >= 0.0  # measured
    assert health["baseline"]["from"] == "learning"

    # Home Assistant: the sensors read R/health, with units and a state class
    snap = retained_snapshot(rig.broker.port, f"{PREFIX}/#")
    node = "rotorbridge_rotor_r_tower"
    cw = json.loads(snap[f"{PREFIX}/sensor/{node}/speed_cw/config"])
    assert cw["state_topic"] == rig.t("health") and cw["state_class"] == "measurement"
    assert cw["unit_of_measurement"] == "°/s"
    shown = float(render(cw["value_template"], json.dumps(health)))
    assert shown == pytest.approx(speed, rel=0.1)
    odometer = json.loads(snap[f"{PREFIX}/sensor/{node}/odometer/config"])
    assert odometer["state_class"] == "total_increasing"
    assert float(render(odometer["value_template"], json.dumps(health))) == health["odometer_deg"]
    moves = json.loads(snap[f"{PREFIX}/sensor/{node}/moves/config"])
    assert render(moves["value_template"], json.dumps(health)) == "6"
    problem = json.loads(snap[f"{PREFIX}/binary_sensor/{node}/health_problem/config"])
    assert problem["device_class"] == "problem"
    assert render(problem["value_template"], json.dumps(health)) == "OFF"
    reset = json.loads(snap[f"{PREFIX}/button/{node}/health_reset/config"])
    assert reset["command_topic"] == rig.t("health/reset")

    # a restart: what was learned comes back from the state file, not from the broker
    rig.stop()
    rig.probe.publish(rig.t("health"), "", retain=True)  # the broker forgets it
    stored = json.loads((rig.tmp / "state.json").read_text())
    assert stored["rotators"]["tower"]["health"]["moves"] == 6
    t_restart = rig.probe.caught_up()
    rig.start()
    rig.ready("tower", after=t_restart)
    back = rig.probe.wait_for(rig.t("health"), lambda m: bool(m.payload), after=t_restart)
    back = json.loads(back.payload)
    assert back["moves"] == 6 and back["odometer_deg"] == health["odometer_deg"]
    assert back["speed_cw_deg_s"] == health["speed_cw_deg_s"]
    after = _move(rig, 200, 7)
    assert after["moves"] == 7
    assert after["speed_cw_deg_s"] == pytest.approx(speed, rel=0.1)


def test_a_retained_reset_is_refused_and_a_live_one_starts_a_new_baseline(rig: Rig) -> None:
    rig.add("tower", emu={"start_az_deg": 20}, health_baseline_moves=3)
    rig.start()
    rig.ready("tower")
    for n in range(1, 4):
        health = _move(rig, 200 if n % 2 else 20, n)
    assert health["baseline"]["from"] == "learned"
    t0 = time.monotonic()
    rig.probe.publish(rig.t("health/reset"), "RESET", retain=True)
    error = rig.probe.wait_for(rig.t("error"), after=t0)
    assert "retained command" in json.loads(error.payload)["message"]
    rig.probe.publish(rig.t("health/reset"), "", retain=True)  # cleared again
    assert json.loads(rig.retained()[rig.t("health")])["baseline"]["from"] == "learned"
    t1 = time.monotonic()
    rig.probe.publish(rig.t("health/reset"), "RESET")
    msg = rig.probe.wait_for(
        rig.t("health"), lambda m: json.loads(m.payload)["baseline"]["from"] == "learning", after=t1
    )
    reset = json.loads(msg.payload)
    assert reset["moves"] == 3 and reset["baseline"]["moves_to_learn"] == 3
    assert reset["baseline"]["speed_cw_deg_s"] is None
