"""Groups: rotators turned together from one topic (``[[groups]]``, settings/groups.py). Pure:
what a group's target asks of each member, and the group's status from its members'. The
service (service.py rule 10) hands each member's part to that member's own judge and the
group's stop to the last word (halts.py), as a stop of every member.

Rules:
1. A group's target is a bearing, or an azimuth and an elevation (the payloads of a rotator's
   ``R/target``); a place or a call is refused (each member would point at it from where it
   stands, not with the group's offsets). An elevation is refused, for the whole group, unless
   every member has an elevation axis: nothing moves.
2. Each member's part is one ``Target``: the group's azimuth plus the member's offset, brought
   into 0..360; the elevation as given. A member with an offset is sent a bearing that names
   no end of its travel (``Target.az_either_end``): where its raw value is 0 and 360, the two
   ends of the travel (a GS-232's, a RotorCard's, a SatEL's, an Easycomm's, a Prosistel's, an
   RC2800's), its judge takes the end nearer the rotor (pointing.py rule 2; attack 10: the
   group's 180 with offset 180, folded to 0, went to a GS-232 at 355 as ``M000``, a turn of
   355 degrees back through south, and no group bearing named 360 for it). A member without an
   offset gets the group's bearing as its own target names it: 360 is 360, 0 the other end.
   The group's azimuth itself must be 0..360 (an
   offset would make 361 a bearing the member takes); the refusal shows it as sent. A part
   outside the member's group limits (true bearings, after its offset; north is 0 and 360
   alike) is that member's refusal, decided here, quoting the bearing with the digits that
   keep it past them (core/text.py ``shown_past``; review 87: ``340.0000004`` past 20..340
   was "340 is outside upper's limits ... (20..340)"); a part inside them carries them, and the
   member's judge keeps the turn inside them too (pointing.py rule 9).
3. The others still turn: a member's refusal, here or by its own judge (its limits, its lock,
   the wind, its lease, its link), is reported on the group's error topic and in the group's
   status, and costs the other members nothing (docs/groups.md says why).
4. The group's status is its members' (each one's bearing, elevation, state, availability)
   with the refusals of the group's last target; the group's bearing is its first available
   member's less that member's offset (a review: an unplugged first member's last reading was
   shown while the others turned elsewhere). A group is available while any member is: a
   stop must reach whichever member can still hear one.
5. A group takes a target and a stop, nothing else: it has no lock (each member has its own);
   a rotator's other commands sent to a group's topics are refused (service.py rule 10).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass

from bridge.core.model import MotionState, Origin, RotatorStatus, Source, Target
from bridge.core.text import shown_past
from bridge.interfaces.mqtt import payloads as pl


@dataclass(frozen=True)
class Member:
    id: str
    offset_deg: float = 0.0
    limits_deg: tuple[float, float] | None = None  # true bearings, after the offset (rule 2)


@dataclass(frozen=True)
class Group:
    id: str
    name: str
    members: tuple[Member, ...]

    @property
    def member_ids(self) -> tuple[str, ...]:
        return tuple(m.id for m in self.members)


@dataclass(frozen=True)
class Part:
    """One member's part of a group's target: a target for its judge, or why none (rule 2)."""

    member: str
    target: Target | None
    refused: str | None = None


def member_bearing(az_deg: float, offset_deg: float) -> float:
    """Rule 2: a member's azimuth for the group's ``az_deg``, brought into 0..360 (a member
    without an offset gets the group's bearing as sent: 360 stays 360; with one, north is 0
    here and its part names neither end, which its judge picks)."""
    return az_deg if offset_deg == 0 else (az_deg + offset_deg) % 360.0


def _inside(az_deg: float, lo_hi: tuple[float, float]) -> bool:
    """Rule 2: a bearing inside a member's limits, north as either 0 or 360 (an attack pass:
    ``360``, Home Assistant's top, was refused for limits 0..90, and the group's 180 with an
    offset of 180 for limits 340..360)."""
    lo, hi = lo_hi
    return any(lo <= az_deg + turn <= hi for turn in (0.0, 360.0, -360.0))


def _exact(value: float) -> str:
    """Rule 2's refusal: the azimuth as sent, short where that is exact (an attack pass:
    ``360.0001`` was refused as "not 360")."""
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


def fan_out(
    group: Group,
    payload: bytes,
    has_elevation: Mapping[str, bool],
    origin: Origin | None = None,
) -> list[Part]:
    """The group target ``payload`` as each member's part (rules 1 and 2); PayloadError when
    it is no target for a group (nothing moves)."""
    aim = pl.parse_aim(payload)
    if not isinstance(aim, tuple):
        raise pl.PayloadError(
            "a group turns to a bearing (or an azimuth and an elevation): a place or a call is "
            "sent to each rotator's own target topic"
        )
    az, el = aim
    if not 0 <= az <= 360:  # an offset must not turn a bearing no rotator takes into one
        raise pl.PayloadError(f"a group's azimuth is a bearing 0..360, not {_exact(az)}")
    if el is not None:
        flat = [m.id for m in group.members if not has_elevation.get(m.id, False)]
        if flat:
            raise pl.PayloadError(
                f"an elevation for group {group.id}, but {', '.join(flat)} "
                f"{'turns' if len(flat) == 1 else 'turn'} in azimuth only"
            )
    parts = []
    for m in group.members:
        member_az = member_bearing(az, m.offset_deg)
        lo_hi = m.limits_deg
        if lo_hi is not None and not _inside(member_az, lo_hi):
            parts.append(
                Part(
                    m.id,
                    None,
                    f"{shown_past(member_az, *lo_hi, around=True)} is outside {m.id}'s limits "
                    f"in group {group.id} "
                    f"({lo_hi[0]:g}..{lo_hi[1]:g})",
                )
            )
            continue
        either = m.offset_deg != 0  # rule 2: its bearing names no end of its travel
        target = Target(
            member_az, el, Source.MQTT, origin=origin, within_deg=lo_hi, az_either_end=either
        )
        parts.append(Part(m.id, target))
    return parts


def refusals_json(group: Group, command: str, refused: Mapping[str, str]) -> str:
    """The group's error event (rule 3): which members did not take the command, and why;
    whether any other did (none: nothing turns)."""
    names = ", ".join(refused)
    others = "the others turn" if set(group.member_ids) - set(refused) else "none turns"
    doc = {
        "kind": "refused",
        "command": command,
        "message": f"group {group.id}: not taken by {names}; {others}",
        "members": dict(refused),
    }
    return json.dumps(doc, separators=(",", ":"))


def group_available(statuses: Mapping[str, RotatorStatus | None]) -> bool:
    """Rule 4: while any member is available."""
    return any(s is not None and s.available for s in statuses.values())


def group_state(statuses: Mapping[str, RotatorStatus | None]) -> MotionState:
    """Moving while any member is read turning, available or not (a composite's azimuth box
    turning on while its elevation box is out: an attack pass found the group said idle);
    offline when none is available; else the first member's state that is not idle, or
    idle."""
    if any(s is not None and s.state is MotionState.MOVING for s in statuses.values()):
        return MotionState.MOVING
    known = [s for s in statuses.values() if s is not None and s.available]
    if not known:
        return MotionState.OFFLINE
    for s in known:
        if s.state is not MotionState.IDLE:
            return s.state
    return MotionState.IDLE


def group_bearing(group: Group, statuses: Mapping[str, RotatorStatus | None]) -> float | None:
    """Rule 4: the first available member with a bearing, less its offset (none available: the
    first with a bearing, the last one known)."""
    for available in (True, False):
        for m in group.members:
            s = statuses.get(m.id)
            if s is not None and s.bearing_deg is not None and (s.available or not available):
                return round((s.bearing_deg - m.offset_deg) % 360.0, 1) % 360.0  # 359.97: 0.0
    return None


def status_json(
    group: Group,
    statuses: Mapping[str, RotatorStatus | None],
    refused: Mapping[str, str],
) -> str:
    """The group's retained status (rule 4)."""
    members = {}
    for m in group.members:
        s = statuses.get(m.id)
        members[m.id] = {
            "bearing": None if s is None else s.bearing_deg,
            "elevation": None if s is None else s.elevation_deg,
            "state": MotionState.OFFLINE.value if s is None else s.state.value,
            "available": s is not None and s.available,
            "offset": m.offset_deg,
        }
    doc = {
        "bearing": group_bearing(group, statuses),
        "state": group_state(statuses).value,
        "moving": any(s is not None and s.moving for s in statuses.values()),
        "available": group_available(statuses),
        "members": members,
        "refused": dict(refused),
    }
    return json.dumps(doc, separators=(",", ":"))
