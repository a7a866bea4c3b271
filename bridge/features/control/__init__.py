"""Who is turning it, as one feature (bridge/feature.py): the control lease (one operator
holds the rotator for a while; the others are refused) and its release.

What it is made of:
- its keys: ``control_*`` in ``[[rotators]]`` (settings/rotator.py);
- the lease: runtime/lease.py (pure), judged by runtime/rotator.py (runtime/operators.py: the
  judge's lease and the audit trail), saved by the state writer; no session part (the judge,
  not the session's step, keeps it);
- payload.py: a claim's and a release's payloads, ``R/control``;
- here: ``R/control/claim``, ``R/control/release``, ``R/control``, its Home Assistant sensor
  and button, its declaration. (``control`` in ``R/status`` and ``R/audit`` are the core's:
  every command's audit is the judge's.)
"""

from __future__ import annotations

from bridge.core.model import Claim, Origin, Release, RotatorStatus, Source
from bridge.feature import CommandTopic, EntityRow, Feature, RotatorView, StateTopic
from bridge.features.control.payload import control_json, parse_claim, parse_release

NAME = "control"
STATE = "control"  # R/control: who holds the lease, until when (retained)
CLAIM = "control/claim"
RELEASE = "control/release"
RELEASE_PAYLOAD = '{"operator": "homeassistant"}'  # who pressed Home Assistant's button
AFTER = "last_error"  # its entities' place in discovery: after rotor health's (feature.py rule 5)


def _claim(payload: bytes, by: Origin) -> Claim:
    """payload.py rule 1 (an empty payload is its error to name)."""
    operator, minutes = parse_claim(payload, by.operator)
    return Claim(operator, minutes, source=Source.MQTT, origin=by)


def _release(payload: bytes, by: Origin) -> Release:
    """payload.py rule 2: any payload; the message's operator, else the payload's."""
    named = parse_release(payload) if by.operator is None else None
    return Release(source=Source.MQTT, origin=by if named is None else Origin(Source.MQTT, named))


def _status(status: RotatorStatus) -> RotatorStatus:
    return status


def _control(status: RotatorStatus) -> str:
    return control_json(status.control)


def _sensor(r: RotatorView) -> dict[str, object]:
    """The lease's holder, its end as an attribute."""
    return {
        "state_topic": r.topics.feature(STATE), "json_attributes_topic": r.topics.feature(STATE),
        "value_template": "{{ value_json.holder or 'free' }}", "icon": "mdi:account-lock",
    }  # fmt: skip


def _button(r: RotatorView) -> dict[str, object]:
    """Anyone may release it: the station owner's button."""
    return {
        "command_topic": r.topics.feature(RELEASE), "payload_press": RELEASE_PAYLOAD,
        "icon": "mdi:lock-open-variant",
    }  # fmt: skip


FEATURE = Feature(
    name=NAME,
    docs="docs/mqtt.md#who-is-turning-it-operators-the-control-lease-and-the-audit-trail",
    summary="one operator holds the rotator for a while; the others are refused",
    commands=(
        CommandTopic(CLAIM, "claim", _claim, takes_empty=True),
        CommandTopic(RELEASE, "release", _release, takes_empty=True),
    ),
    states=(StateTopic(STATE, _status, _control, after_status=True, remote=True),),
    entities=(
        EntityRow("sensor", "control", "Control", _sensor, bridge_only=True, after=AFTER),
        EntityRow(
            "button", "release_control", "Release control", _button, bridge_only=True, after=AFTER
        ),
    ),
    console=(
        "the lease line of the rotator's card and its claim (interfaces/web/static/console.js)",
    ),
)
