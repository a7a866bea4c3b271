"""R/health and R/health/reset through the MQTT service (recorded, no broker): the report goes
out once per move, not at every status; ``R/status`` carries it too; a reset is a command that
a retained message never carries out."""

from __future__ import annotations

import dataclasses
import json

from bridge.core.model import AxisHealth, RotatorHealth, RotatorStatus
from bridge.features.health.payload import health_doc
from bridge.interfaces.mqtt import payloads as pl
from tests.mqtt.test_service import RecordingRotator, service

HEALTH = RotatorHealth(
    az=AxisHealth(5.9, 4.1, 6.0, 5.6, 1.0, 1.2, 0.5, 26410.0),
    start_delay_s=0.31,
    baseline_start_delay_s=0.3,
    baseline_from="learned",
    moves=142,
    stalls=1,
    stall_azimuths_deg=(127.0,),
    motor_on_s=4520.33,
    warnings=("counter-clockwise 4.1 °/s, 27 % below its baseline 5.6 over its last 7 moves",),
)


def test_health_is_published_once_per_report_not_per_status() -> None:
    svc, pub, _ = service({"tower": "rotorez"})
    for bearing in (10.0, 11.0, 12.0):  # three polls, one report
        svc.publish_status("tower", RotatorStatus("tower", bearing_deg=bearing, health=HEALTH))
    sent = [p for t, p, _ in pub.take() if t == "rotor/health"]
    assert len(sent) == 1
    doc = json.loads(sent[0])
    assert doc["speed_cw_deg_s"] == 5.9 and doc["speed_ccw_deg_s"] == 4.1
    assert doc["start_delay_s"] == 0.31 and doc["coast_deg"] == 1.0
    assert (doc["moves"], doc["stalls"], doc["odometer_deg"]) == (142, 1, 26410.0)
    assert doc["stall_azimuths"] == [127.0]
    assert doc["baseline"] == {
        "from": "learned",
        "moves_to_learn": 0,
        "speed_cw_deg_s": 6.0,
        "speed_ccw_deg_s": 5.6,
        "start_delay_s": 0.3,
        "coast_deg": 1.2,
    }
    assert doc["warnings"] == list(HEALTH.warnings)
    status = json.loads(pub.retained["rotor/status"])
    assert status["health"] == doc  # the console reads it there


def test_a_controller_without_readings_says_so() -> None:
    assert health_doc(RotatorHealth(measured=False)) == {
        "measured": False,
        "reason": "the controller reports no position",
    }


def test_status_without_health_is_unchanged() -> None:
    doc = json.loads(pl.status_json(RotatorStatus("tower"), 0.0, False))
    assert "health" not in doc


def test_reset_is_a_command_and_never_taken_retained() -> None:
    svc, _pub, rots = service({"tower": "rotorez"})
    rot = RecordingRotator("tower", "rotorez")  # a reset: ("reset_health",)
    svc.attach(rot)
    svc.on_message("rotor/health/reset", b"RESET", retain=True)
    assert rot.calls[0][0] == "refused" and "retained" in str(rot.calls[0][1])
    svc.on_message("rotor/health/reset", b"RESET", retain=False)
    assert rot.calls[-1] == ("reset_health",)


def test_an_empty_reset_is_refused_not_taken() -> None:
    """MQTT 3.1.1: deleting a retained R/health/reset while the bridge is connected reaches it
    as an empty plain message (service.py rule 1); it must not throw away what was learned."""
    svc, _pub, _rots = service({"tower": "rotorez"})
    rot = RecordingRotator("tower", "rotorez")  # a reset: ("reset_health",)
    svc.attach(rot)
    svc.on_message("rotor/health/reset", b"", retain=False)
    assert rot.calls and rot.calls[0][0] == "refused" and "empty" in str(rot.calls[0][1])
    assert ("reset_health",) not in rot.calls


def test_each_report_s_text_is_its_own_whatever_was_rendered_before() -> None:
    """The text is kept by the report (the same object from status to status): a new report,
    equal or not, many of them (more than are kept), each says itself in R/health and
    R/status."""
    svc, pub, _ = service({"tower": "rotorez"})
    for moves in [*range(100), 5, 5]:
        report = dataclasses.replace(HEALTH, moves=moves)
        for bearing in (10.0, 11.0):
            svc.publish_status("tower", RotatorStatus("tower", bearing_deg=bearing, health=report))
        assert json.loads(pub.retained["rotor/health"])["moves"] == moves
        assert json.loads(pub.retained["rotor/status"])["health"] == health_doc(report)
