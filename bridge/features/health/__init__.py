"""Rotor health, as one feature (bridge/feature.py): how the rotor turns (its speeds, start
delay, coast, odometer), judged against a baseline it learnt, with its warnings.

What it is made of:
- its keys in ``[[rotators]]``: ``health_*`` in settings/rotator.py;
- its session part: session/health.py ``Health`` (the judge: session/health_judge.py, its
  memory: runtime/health_memory.py, saved by the state writer), run by the session's step
  as ``PART`` here says;
- payload.py: ``R/health`` and the ``health`` block of ``R/status``, rendered once per move;
- here: ``R/health/reset``, ``R/health``, its Home Assistant sensors and button, its
  declaration; the console's health line (interfaces/web/static/console.js ``renderHealth``) reads
  the status's block.
"""

from __future__ import annotations

from bridge.core.model import Origin, ResetHealth, RotatorHealth, RotatorStatus, Source
from bridge.feature import CommandTopic, EntityRow, Feature, RotatorView, StateTopic, StatusBlock
from bridge.features.health.payload import health_json
from bridge.interfaces.mqtt.payloads import parse_press
from bridge.session.parts import Part, Scene, Wake
from bridge.session.session import RotatorSession

NAME = "health"
STATE = "health"  # R/health: the last report, retained
RESET = "health/reset"  # R/health/reset: a new baseline (after a repair)
DIAGNOSTIC = {"entity_category": "diagnostic"}
AFTER = "last_error"  # its entities' place in discovery (bridge/feature.py rule 5)


def _health(status: RotatorStatus) -> RotatorHealth | None:
    return status.health


def _reset(payload: bytes, by: Origin) -> ResetHealth:
    """A press (payloads.py ``parse_press``): it moves nothing, so no lease is asked."""
    parse_press(payload, "reset rotor health", "RESET")
    return ResetHealth(source=Source.MQTT, origin=by)


def _sensor(oid: str, name: str, field: str, unit: str, kind: str, needs: str) -> EntityRow:
    """Long-term statistics keep the trend; kept while the rotator is offline too."""

    def config(r: RotatorView) -> dict[str, object]:
        return {
            "state_topic": r.topics.feature(STATE), "unit_of_measurement": unit,
            "state_class": kind,
            "value_template": f"{{{{ value_json.{field} }}}}",  # null: None, unknown to HA
            **({"device_class": "duration"} if unit == "s" else {}), **DIAGNOSTIC,
        }  # fmt: skip

    return EntityRow("sensor", oid, name, config, needs=needs, bridge_only=True, after=AFTER)


NUMBERS = (  # object id, name, R/health field, unit, state class, what it needs
    ("speed_cw", "Speed clockwise", "speed_cw_deg_s", "°/s", "measurement", "can_report_position"),
    ("speed_ccw", "Speed counter-clockwise", "speed_ccw_deg_s", "°/s", "measurement",
     "can_report_position"),
    ("speed_up", "Speed up", "speed_up_deg_s", "°/s", "measurement", "el_health"),
    ("speed_down", "Speed down", "speed_down_deg_s", "°/s", "measurement", "el_health"),
    ("start_delay", "Start delay", "start_delay_s", "s", "measurement", "can_report_position"),
    ("coast", "Coast after a stop", "coast_deg", "°", "measurement", "can_report_position"),
    ("odometer", "Odometer", "odometer_deg", "°", "total_increasing", "can_report_position"),
    ("moves", "Moves", "moves", "moves", "total_increasing", "can_report_position"),
    ("stalls", "Stalls", "stalls", "stalls", "total_increasing", "can_report_position"),
    ("motor_on", "Motor-on time", "motor_on_s", "s", "total_increasing", "can_report_position"),
)  # fmt: skip


def _problem(r: RotatorView) -> dict[str, object]:
    return {
        "state_topic": r.topics.feature(STATE), "device_class": "problem",
        "value_template": "{{ 'ON' if value_json.warnings else 'OFF' }}",
        "json_attributes_topic": r.topics.feature(STATE),  # the warnings, numbers, baseline
    }  # fmt: skip


def _reset_button(r: RotatorView) -> dict[str, object]:
    return {
        "command_topic": r.topics.feature(RESET), "payload_press": "RESET", **DIAGNOSTIC,
        "icon": "mdi:restart",
    }  # fmt: skip


def _step_part(s: RotatorSession, scene: Scene) -> None:
    s.health.speed_factor = s.controller.options.speed_factor()  # (health.py rule 9)
    s.health.step(scene.motion, scene.now)  # (its report is in the status)


def _reset_part(s: RotatorSession, now: float) -> None:
    s.health = s.health.rebuilt(s.cfg)  # health.py rule 7


# its session part (parts.py rule 4): it measures, after the poll
PART: Part[RotatorSession] = Part(
    "health",
    Wake.MOTION,  # it measures moves from the motion (health.py rule 6)
    False,
    lambda s: True,
    _step_part,
    _reset_part,
)

FEATURE = Feature(
    name=NAME,
    docs="docs/mqtt.md#rotor-health",
    summary="how the rotor turns, against a baseline it learnt, with warnings",
    commands=(CommandTopic(RESET, "health_reset", _reset),),
    states=(StateTopic(STATE, _health, health_json, new_only=True),),
    status=(StatusBlock("health", _health, health_json, rendered=True),),
    entities=(
        *(_sensor(*row) for row in NUMBERS),
        EntityRow(
            "binary_sensor",
            "health_problem",
            "Rotor health",
            _problem,
            needs="can_report_position",
            bridge_only=True,
            after=AFTER,
        ),
        EntityRow(
            "button",
            "health_reset",
            "Reset rotor health",
            _reset_button,
            needs="can_report_position",
            bridge_only=True,
            after=AFTER,
        ),
    ),  # fmt: skip
    part=PART,
    console=(
        "the health line of the rotator's card (interfaces/web/static/console.js renderHealth)",
    ),
)
