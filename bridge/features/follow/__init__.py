"""Following WSJT-X, as one feature (bridge/feature.py): the rotor turns to the station WSJT-X
or JTDX is working, while ``R/follow`` says so.

What it is made of:
- its keys: ``follow_*`` in ``[[rotators]]`` (settings/pointing.py) and ``[wsjtx]``
  (settings/wsjtx.py); WSJT-X's UDP messages: wsjtx/ (the listener hands each Status to the
  rotators as an input);
- its session part: session/follow.py ``Follower`` (started and ended as a command:
  session/feature_commands.py), run by the session's step as ``PART`` here says;
- ``R/follow``'s payload: interfaces/mqtt/payloads.py ``parse_follow`` (beside the other commands'
  words);
- here: ``R/follow``, ``R/follow/state``, its ``following`` and ``following_ended`` blocks in
  ``R/status``, its Home Assistant switch and sensor, its declaration.
"""

from __future__ import annotations

from bridge.core.model import FollowingInfo, FollowQso, Origin, RotatorStatus, Source
from bridge.feature import CommandTopic, EntityRow, Feature, RotatorView, StateTopic, StatusBlock
from bridge.interfaces.mqtt.payloads import parse_follow
from bridge.session.parts import Part, Wake
from bridge.session.session import RotatorSession

NAME = "follow"
COMMAND = "follow"  # R/follow: wsjtx, off, or JSON with the path
STATE = "follow/state"  # R/follow/state: what is followed, or off
NEEDS = "can_follow"  # [wsjtx] on and a station (the rotator's and RotatorInfo's)


def _follow(payload: bytes, by: Origin) -> FollowQso:
    on, long_path = parse_follow(payload)
    return FollowQso(on, long_path, source=Source.MQTT, origin=by)


def following_json(info: FollowingInfo) -> dict[str, object]:
    """The status's ``following`` block: whom WSJT-X names, and where the rotor was turned."""
    return {
        "source": info.source,
        "path": info.path,
        "call": info.call,
        "grid": info.grid,
        "bearing": None if info.bearing_deg is None else round(info.bearing_deg, 1),
        "distance_km": None if info.distance_km is None else round(info.distance_km, 1),
        "held": info.held,
    }


def follow_state(status: RotatorStatus) -> str:
    """``R/follow/state``: what is followed (``wsjtx``), or ``off``."""
    return status.following.source if status.following is not None else "off"


def _status(status: RotatorStatus) -> RotatorStatus:
    return status


def _following(status: RotatorStatus) -> FollowingInfo | None:
    return status.following


def _ended(status: RotatorStatus) -> str | None:
    return status.following_ended


def _switch(r: RotatorView) -> dict[str, object]:
    return {
        "command_topic": r.topics.feature(COMMAND), "state_topic": r.topics.feature(STATE),
        "payload_on": "wsjtx", "payload_off": "off", "state_on": "wsjtx", "state_off": "off",
        "icon": "mdi:account-arrow-right",
    }  # fmt: skip


def _followed(r: RotatorView) -> dict[str, object]:
    return {
        "state_topic": r.topics.status, "icon": "mdi:account-voice",
        "value_template": "{{ value_json.following.call if value_json.following is defined "
                          "and value_json.following.call else 'None' }}",
    }  # fmt: skip


# its session part (parts.py rule 4)
PART: Part[RotatorSession] = Part(
    "following",
    Wake.STEP,  # each of its steps is activity for auto-park
    True,
    lambda s: s.follower.on,
    lambda s, scene: s.follower.step(scene),
    lambda s, now: s.features.end("internal error", tracking=False),
)

FEATURE = Feature(
    name=NAME,
    docs="docs/follow.md",
    summary="turns to the station WSJT-X or JTDX is working",
    commands=(CommandTopic(COMMAND, "follow", _follow),),
    states=(StateTopic(STATE, _status, follow_state, needs=NEEDS),),
    status=(
        StatusBlock("following", _following, following_json),
        StatusBlock("following_ended", _ended, str, kind=str),
    ),
    entities=(
        EntityRow("switch", "follow", "Follow WSJT-X", _switch, needs=NEEDS, after="distance"),
        EntityRow(
            "sensor", "followed", "Followed station", _followed, needs=NEEDS, after="distance"
        ),
    ),
    part=PART,
)
