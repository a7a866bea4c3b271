"""One axis of a box, and a rotator made of two boxes (azimuth from one, elevation from the
other): the model specs and the codecs that let one controller serve one axis only.

A composite rotator (settings/rotator.py ``azimuth`` / ``elevation``, runtime/composite.py)
turns its azimuth with one controller and its elevation with another. Each box keeps its own
codec; this module wraps it so that the session driving that box sees one axis only.

Rules:
1. Any model drives the azimuth. Its elevation, if it has one, is never turned and never
   read: the azimuth box's spec has no elevation and its codec reports none. An az/el box's
   codec still writes an elevation in every target (GS-232's ``W``, SPID's frame): it is sent
   the elevation the box last reported for itself (as rule 2 does for an elevation box's
   azimuth), never the horizon, which every az/el codec writes for an elevation left out;
   within the box's own elevation range (a box parked at -0.5 reports it, and its codec
   writes nothing below 0: sent as it was, every azimuth target raised), at the step of its
   grid it reads (``_held``: a Rot2Prog at 0.25 degrees reads 44.25 as 44.2, which it would
   take as 44.0, spid.py rule 6). What the box says of that elevation is judged by no range
   (base.py ScalesElevation, rule 10): past its axis's slack it spoils nothing, the azimuth
   in the same reply read as ever (review 98: a G-5500's box whose elevation input read
   ``EL=190``, an Easycomm's ``EL181.0``, had its whole reply spoiled, the rotator offline
   for good as "garbled replies", its azimuth never turned), and is sent back within the
   range as above.
2. The elevation box reports where it points and is either an az/el box used for its
   elevation, or a one-axis box made to turn an elevation rotor (ONE_AXIS_ELEVATION: Green
   Heron sells the RT-21 for either axis); a one-axis azimuth controller (a Rotor-EZ, a GS-232
   azimuth box) is no elevation box. An az/el box's azimuth is never turned: every target it
   is sent carries the azimuth the box last reported for itself (at its step, as in rule
   1), whatever azimuth the session asked for, and is read whatever its codec would judge of
   it as a model's scale (base.py ScalesAzimuth: a GS-232 at P45 configured as gs232b, its
   azimuth resting at 400, was a MISFIT at every reply, review 49). A one-axis box is sent
   the elevation as its one bearing, and its bearing is read as the elevation (0..180 of its
   range). Either reports back as its azimuth the one the session last asked for (before
   any: an az/el box the first it said of itself, kept, a one-axis box 0), so that the
   session's motion machine sees that axis arrive at once and judges the elevation alone
   (review 49: an az/el box's own azimuth shown as it read, turned by hand from its panel,
   was told as the rotor turning, or shown MOVING, the antenna standing still).
   What the box said of itself counts once the engine took it as a reading (TakesReadings):
   a well-formed glitch that a second reply spoils (link.py rule 9) is never sent back.
   A one-axis box's bearing outside the elevation axis's scale (0..180 of its range, up to
   EL_READ_SLACK_DEG past an end read as that end, base.py rule 10's pot slack, as gs232.py
   rule 2 reads a GS-232 past an end: a pot a degree or two off with the weather, a coast
   past the end; the box's own codec reads within the same slack past its own scale's ends
   first, a Prosistel D's 091 as 90, prosistel.py rule 1, attack 30; below 0 on a
   box whose bearings wrap, as the RT-21's do, 0.0..359.9, whose horizon a little low reads
   359.x: that too is the bottom end, read as 0; review 49: with half a degree, an RT-21
   reading 181 at its end was offline for good, no target ever turning it back) is
   no elevation: a MISFIT (protocols/base.py: told on R/error in words that say so, once
   such replies persist, controller.py rule 6), never a
   reading, and the elevation it last said is forgotten: no target goes to that box (NotReady:
   the engine asks, and sends once it reads an elevation again, a reading taken), as the box
   would turn from a bearing nobody knows. (Attack 12: an RT-21 reading 300, a pot past its
   end or a box calibrated for an azimuth rotor, was published as elevation 300 with
   el_max_deg 90, nothing said, and the next target's elevation 30 turned the box 270
   degrees down from there.)
3. A stop is the box's own stop (on an az/el box, both its axes stop: the azimuth is still).
4. The composite's spec is data like any: the azimuth's range from the azimuth box, the
   elevation's from the elevation box, no options (each box keeps its own defaults); it
   reports a position only when both boxes can, and takes whole degrees when either does; it
   reports a version when either box does (runtime/composite.py rule 3: theirs, joined), so
   Home Assistant has its version entity as a single controller's (a review: it had none,
   though ``R/version`` and the device's firmware said the boxes' pair).
5. What the box says of its axis that is never turned counts only when two readings taken
   in a row say so, a connection's first value too (until then no target is counted: a target
   waits one reading more after each connect; when none of KEEP_FIRST_READINGS agree, a
   jittering or floating input, the latest counts, or no target would ever go), and a change
   beyond KEEP_NOISE_DEG likewise:
   that axis does not move, so a change is line noise or a hand at the box's panel, and a
   glitch sent back turns that rotor (an attack pass: one flipped bit read the elevation
   box's own azimuth 150 as 350, and the next elevation target wrote ``W350 030``: its
   azimuth rotor turned 200 degrees; a review: the first reading after a replug likewise).
   The session's readings of the axis it drives are judged by its own rules
   (session/controller.py rule 9).
6. A box made for an elevation rotor alone (BEARING_IS_ELEVATION: a Prosistel D as
   ``prosistel-el``), configured as a rotator of its own, has one bearing, and it is the
   elevation (``bearing_is_elevation``): whatever the bridge itself works out as an azimuth
   is never its target. It is no member of a group (settings/groups.py: a group's bearing is
   an azimuth), and it neither tracks nor follows, nor turns to a place (a locator, a
   coordinate, a DX cluster's call, a logger's locator), each refused by the judge
   (session/feature_commands.py rule 6): the body's azimuth (tracking.py rule 6), the QSO
   partner's bearing, the place's great-circle bearing. A number sent as its bearing
   (``R/target``, rotctld's ``P``, a logger's heading, N1MM's ``*`` included) is taken as
   that box's bearing, as the user sent it: nothing says which angle the sender meant.
   (Attack 19: ``R/track sun`` raised such a dish to the sun's azimuth, 65 for a sun 22 up,
   under "tracking"; ``R/follow wsjtx`` to a partner's bearing, 42.)
"""

from __future__ import annotations

import enum
from dataclasses import replace

from bridge.core.geo import apart_deg
from bridge.protocols.base import (
    POT_SLACK_DEG,
    Codec,
    HalfLine,
    HamlibRotType,
    HoldsOnGrid,
    JunkReason,
    JunkReply,
    ModelSpec,
    NotReady,
    PacedConnect,
    PositionReply,
    Reply,
    ScalesAzimuth,
    ScalesElevation,
    StopsOnTheLine,
    TakesReadings,
    WatchesWrites,
)

# positions fed but not yet taken or dropped (link.py rule 9): one exchange's, and a few spare
_PENDING = 4
KEEP_NOISE_DEG = 2.0  # rule 5: a change of the axis never turned up to this is believed at once
KEEP_FIRST_READINGS = 3  # rule 5: a first value none of this many agree on: the latest


class Axis(enum.StrEnum):
    AZIMUTH = "azimuth"
    ELEVATION = "elevation"


# rule 2: one-axis boxes made to turn an elevation rotor as well as an azimuth one
# (prosistel-el: a D box, unit E; prosistel-el-a: one answering as unit A)
ONE_AXIS_ELEVATION = frozenset({"rt21", "prosistel-el", "prosistel-el-a"})
ONE_AXIS_EL_MAX_DEG = 180.0
# rule 2: a one-axis box's bearing this far past an end reads as the end (base.py rule 10)
EL_READ_SLACK_DEG = float(POT_SLACK_DEG)
# ... and of those, the models made for the elevation alone: as a rotator of its own, what such a
# box calls its bearing is an elevation (rule 6: an azimuth would tilt it)
BEARING_IS_ELEVATION = frozenset({"prosistel-el", "prosistel-el-a"})


def bearing_is_elevation(spec: ModelSpec) -> bool:
    """Rule 6: ``spec`` is a box of BEARING_IS_ELEVATION as a rotator of its own (as a
    composite's elevation box, ``axis_spec``, it has an elevation and no such bearing)."""
    return spec.name in BEARING_IS_ELEVATION and not spec.has_elevation


def can_drive(spec: ModelSpec, axis: Axis) -> str | None:
    """Why ``spec`` cannot serve ``axis`` in a composite rotator (None: it can)."""
    if axis is Axis.ELEVATION and not (spec.has_elevation or spec.name in ONE_AXIS_ELEVATION):
        return f"the {spec.display_name} ({spec.name}) has no elevation axis"
    if axis is Axis.ELEVATION and not spec.can_report_position:
        return f"the {spec.display_name} ({spec.name}) cannot report where it points"
    return None


def _held(inner: Codec, deg: float, axis: Axis) -> float:
    """What to ask ``inner`` for to keep ``axis`` where it read ``deg`` (rules 1 and 2: a
    Rot2Prog at 0.25 degrees reads 44.25 as 44.2, and 44.2 asked for is 44.0: base.py
    HoldsOnGrid)."""
    return inner.held(deg, axis.value) if isinstance(inner, HoldsOnGrid) else deg


class AzimuthOnly:
    """Rule 1: ``inner``'s azimuth, and nothing of its elevation."""

    def __init__(self, inner: Codec) -> None:
        self._inner = inner

    def encode_target(self, az_deg: float, el_deg: float | None) -> list[bytes]:
        return self._inner.encode_target(az_deg, None)

    def wire_target(self, az_deg: float, el_deg: float | None) -> tuple[float, float | None]:
        return self._inner.wire_target(az_deg, None)[0], None

    def feed(self, data: bytes) -> list[Reply]:
        return [
            replace(r, el_deg=None) if isinstance(r, PositionReply) else r
            for r in self._inner.feed(data)
        ]

    def encode_stop(self) -> bytes | list[bytes]:
        return self._inner.encode_stop()

    def encode_stop_after(
        self, half: HalfLine, axes: bytes | None = None, ready: bytes | None = None
    ) -> bytes | list[bytes]:
        """base.py rule 9: ``inner``'s stop as the line left off, where it has one."""
        if isinstance(self._inner, StopsOnTheLine):
            return self._inner.encode_stop_after(half, axes, ready)
        return self._inner.encode_stop()

    def encode_query(self) -> bytes | list[bytes] | None:
        return self._inner.encode_query()

    def expire_query(self) -> None:
        self._inner.expire_query()

    def encode_version(self) -> bytes | None:
        return self._inner.encode_version()

    def encode_option(self, name: str, enabled: bool) -> bytes:
        return self._inner.encode_option(name, enabled)

    def awaiting_reply(self) -> bool:
        return self._inner.awaiting_reply()

    def harmless(self, junk: bytes) -> bool:
        return self._inner.harmless(junk)

    def encode_enable(self) -> bytes | None:
        return self._inner.encode_enable()

    def encode_connect(self, now_unix: float) -> list[bytes]:
        return self._inner.encode_connect(now_unix)

    def connect_written(self, frame: bytes) -> None:
        if isinstance(self._inner, PacedConnect):  # (session/link.py rule 14)
            self._inner.connect_written(frame)

    def frame_written(self, frame: bytes) -> None:
        if isinstance(self._inner, WatchesWrites):  # (base.py WatchesWrites)
            self._inner.frame_written(frame)


class _KeepsOwn(AzimuthOnly):
    """What a box said of its other axis counts once the engine took the reading (rules 1
    and 2: TakesReadings), and once said twice if it changed (rule 5); the inner codec is
    told of it too, as its own reply."""

    def __init__(self, inner: Codec) -> None:
        super().__init__(inner)
        self._said: float | None = None  # rule 5: a change said once
        self._unsure = 0  # rule 5: readings of a connection's first value that did not agree
        self._pending: list[tuple[PositionReply, float | None, PositionReply]] = []  # fed:
        # (the reply handed on, what the box said of its other axis, the inner codec's reply)

    def _fed(self, shown: PositionReply, own: float | None, inner: PositionReply) -> None:
        self._pending = [*self._pending[-_PENDING:], (shown, own, inner)]

    def _keep(self, own: float | None, said: float, circle: bool) -> float | None:
        """Rule 5: what to keep of the other axis, ``own`` so far (None: nothing yet, and no
        target is counted: NotReady), now said to be ``said`` (``circle``: an azimuth, 359 and
        0 one degree apart)."""
        if own is not None and apart_deg(own, said, circle) <= KEEP_NOISE_DEG:
            self._said = None
            return said
        if self._said is not None and apart_deg(self._said, said, circle) <= KEEP_NOISE_DEG:
            self._said = None
            return said  # said twice
        self._said = said
        if own is None:  # a connection's first: no two readings agreeing in KEEP_FIRST_READINGS
            self._unsure += 1  # (a jittering or floating input): the latest, as it reads, or
            if self._unsure >= KEEP_FIRST_READINGS:  # no target would ever go (a review: the
                return said  # box asked without end, about 37 times a second)
        return own

    def _taken(self, reply: PositionReply) -> tuple[bool, float | None]:
        """Whether ``reply`` is one fed here, and what it said of the other axis."""
        for i, (fed, own, inner) in enumerate(self._pending):
            if fed is reply:
                del self._pending[: i + 1]
                if isinstance(self._inner, TakesReadings):
                    self._inner.taken(inner)
                return True, own
        return False, None


class AzimuthOfAzEl(_KeepsOwn):
    """Rule 1, for an az/el box: its elevation stays where the box has it."""

    def __init__(self, inner: Codec, el_range: tuple[float, float]) -> None:
        super().__init__(inner)
        if isinstance(inner, ScalesElevation):  # rule 1: its elevation is judged by no range
            inner.elevation_unread()
        self._el_range = el_range  # what its codec writes
        self._own_el: float | None = None  # what the box last said of its elevation, taken

    def wire_target(self, az_deg: float, el_deg: float | None) -> tuple[float, float | None]:
        if self._own_el is None:  # rule 5: said twice first (the engine asks: targets.py)
            raise NotReady("the azimuth box has not said where its elevation is")
        return super().wire_target(az_deg, el_deg)

    def encode_target(self, az_deg: float, el_deg: float | None) -> list[bytes]:
        if self._own_el is None:  # the session sends only once the box answered (a reading)
            raise NotReady("the azimuth box has not said where its elevation is")
        low, high = self._el_range
        el = min(max(_held(self._inner, self._own_el, Axis.ELEVATION), low), high)
        return self._inner.encode_target(az_deg, el)

    def feed(self, data: bytes) -> list[Reply]:
        replies: list[Reply] = []
        for r in self._inner.feed(data):
            if isinstance(r, PositionReply):
                inner, r = r, replace(r, el_deg=None)
                self._fed(r, inner.el_deg, inner)
            replies.append(r)
        return replies

    def taken(self, reply: PositionReply) -> None:
        found, own = self._taken(reply)
        if found and own is not None:
            self._own_el = self._keep(self._own_el, own, circle=False)


class ElevationOnly(_KeepsOwn):
    """Rule 2: ``inner``'s elevation; its azimuth stays where the box has it."""

    def __init__(self, inner: Codec) -> None:
        super().__init__(inner)
        if isinstance(inner, ScalesAzimuth):  # rule 2: its azimuth is judged by no scale
            inner.azimuth_unturned()
        self._own_az: float | None = None  # what the box last said of its azimuth, taken
        self._asked_az: float | None = None  # what the session last asked for
        self._first_az: float | None = None  # rule 2: shown until the session asks for one

    def wire_target(self, az_deg: float, el_deg: float | None) -> tuple[float, float | None]:
        if self._own_az is None:  # rule 5: said twice first (the engine asks: targets.py)
            raise NotReady("the elevation box has not said where its azimuth is")
        return self._inner.wire_target(az_deg, el_deg)

    def encode_target(self, az_deg: float, el_deg: float | None) -> list[bytes]:
        if self._own_az is None:  # the session sends only once the box answered (a reading)
            raise NotReady("the elevation box has not said where its azimuth is")
        frames = self._inner.encode_target(_held(self._inner, self._own_az, Axis.AZIMUTH), el_deg)
        self._asked_az = self._inner.wire_target(az_deg, el_deg)[0]
        return frames

    def feed(self, data: bytes) -> list[Reply]:
        replies: list[Reply] = []
        for r in self._inner.feed(data):
            if isinstance(r, PositionReply):
                inner, own = r, r.az_deg
                if self._first_az is None:
                    self._first_az = own
                shown = self._first_az if self._asked_az is None else self._asked_az
                r = replace(r, az_deg=shown)
                self._fed(r, own, inner)
            replies.append(r)
        return replies

    def taken(self, reply: PositionReply) -> None:
        found, own = self._taken(reply)
        if found and own is not None:
            self._own_az = self._keep(self._own_az, own, circle=True)


class OneAxisElevation(_KeepsOwn):
    """Rule 2: a one-axis box whose one rotor is the elevation, read in ``el_range`` (the
    elevation axis's scale); ``box`` names it in what is said of a bearing outside it;
    ``wraps`` the top of a box whose bearings wrap (360: 359.x is a little below 0)."""

    def __init__(
        self,
        inner: Codec,
        el_range: tuple[float, float] = (0.0, ONE_AXIS_EL_MAX_DEG),
        box: str = "the elevation box",
        wraps: float | None = None,
    ) -> None:
        super().__init__(inner)
        self._el_range = el_range
        self._box = box
        self._wraps = wraps  # rule 2: the bearing a wrapping box says again as 0 (360)
        self._own_el: float | None = None  # what the box last said of its one axis, taken
        self._asked_az: float | None = None  # what the session last asked for
        self._misfit = False  # rule 2: its last bearing was no elevation (none taken since)

    def _ready(self) -> None:
        if self._misfit:  # rule 2
            raise NotReady("the elevation box's last bearing was no elevation")

    def wire_target(self, az_deg: float, el_deg: float | None) -> tuple[float, float | None]:
        self._ready()
        el = self._own_el if el_deg is None else el_deg
        return az_deg, None if el is None else self._inner.wire_target(el, None)[0]

    def encode_target(self, az_deg: float, el_deg: float | None) -> list[bytes]:
        self._ready()
        if el_deg is None and self._own_el is not None:  # (kept where it reads)
            el_deg = _held(self._inner, self._own_el, Axis.AZIMUTH)  # (its one axis)
        el = el_deg
        if el is None:  # the session sends only once the box answered (a reading)
            raise NotReady("the elevation box has not said where it points")
        self._asked_az = az_deg
        return self._inner.encode_target(el, None)

    def feed(self, data: bytes) -> list[Reply]:
        replies: list[Reply] = []
        for r in self._inner.feed(data):
            if isinstance(r, PositionReply):
                low, high = self._el_range
                said = r.az_deg
                if self._wraps is not None and said >= self._wraps - EL_READ_SLACK_DEG:
                    said -= self._wraps  # (a wrapping box a little below its 0: 359.x)
                if not low - EL_READ_SLACK_DEG <= said <= high + EL_READ_SLACK_DEG:
                    replies.append(self._not_elevation(r.az_deg))
                    continue
                az = 0.0 if self._asked_az is None else self._asked_az
                el = min(max(said, low), high)
                inner, r = r, replace(r, az_deg=az, el_deg=el)
                self._fed(r, el, inner)
            replies.append(r)
        return replies

    def _not_elevation(self, deg: float) -> JunkReply:
        """Rule 2: a bearing outside the elevation's scale, said, and the last one forgotten."""
        self._own_el, self._misfit = None, True
        low, high = self._el_range
        return JunkReply(
            b"%g" % deg,
            JunkReason.MISFIT,
            f"{self._box}, turning the elevation, reads {deg:g}, outside {low:g}..{high:g}, "
            "the elevation's scale: no elevation (a pot past its end, or a box calibrated for "
            "an azimuth rotor?); not read as one, and no target is counted from it",
        )

    def taken(self, reply: PositionReply) -> None:
        found, own = self._taken(reply)
        if found:
            self._own_el, self._misfit = own, False


def axis_spec(spec: ModelSpec, axis: Axis) -> ModelSpec:
    """``spec`` as the box of one axis of a composite rotator (rules 1 and 2)."""
    if axis is Axis.AZIMUTH:
        factory = spec.codec_factory
        el_range = (spec.el_min_deg, spec.el_max_deg)
        return replace(
            spec,
            codec_factory=lambda: (
                AzimuthOfAzEl(factory(), el_range) if spec.has_elevation else AzimuthOnly(factory())
            ),
            has_elevation=False,
            el_min_deg=0.0,
            el_max_deg=0.0,
        )
    inner = spec.codec_factory
    if spec.has_elevation:
        return replace(spec, codec_factory=lambda: ElevationOnly(inner()), turns_azimuth=False)
    scale = (max(0.0, spec.az_min_deg), min(ONE_AXIS_EL_MAX_DEG, spec.az_max_deg))
    box = f"the {spec.display_name} ({spec.name})"
    wraps = spec.az_max_deg if spec.az_wraps else None
    return replace(  # a one-axis box turning the elevation
        spec,
        codec_factory=lambda: OneAxisElevation(inner(), scale, box, wraps),
        has_elevation=True,
        turns_azimuth=False,
        el_min_deg=scale[0],
        el_max_deg=scale[1],
        nominal_el_speed_deg_s=spec.nominal_speed_deg_s,
    )


_COMPOSITES: dict[tuple[str, str], ModelSpec] = {}


def composite_spec(az: ModelSpec, el: ModelSpec) -> ModelSpec:
    """The spec of a rotator whose azimuth is ``az``'s and elevation ``el``'s (rule 4); one
    value for each pair of models."""
    key = (az.name, el.name)
    if key not in _COMPOSITES:
        _COMPOSITES[key] = _composite(az, el)
    return _COMPOSITES[key]


def _composite(az: ModelSpec, box: ModelSpec) -> ModelSpec:
    el = axis_spec(box, Axis.ELEVATION)
    return replace(
        az,
        name=f"{az.name}+{box.name}",
        display_name=f"{az.display_name} + {box.display_name}",
        manufacturer=az.manufacturer
        if az.manufacturer == el.manufacturer
        else f"{az.manufacturer} + {el.manufacturer}",
        can_report_position=az.can_report_position and el.can_report_position,
        has_elevation=True,
        has_version=az.has_version or el.has_version,
        settings=(),
        el_min_deg=el.el_min_deg,
        el_max_deg=el.el_max_deg,
        nominal_el_speed_deg_s=el.nominal_el_speed_deg_s,
        reports_while_moving=az.reports_while_moving and el.reports_while_moving,
        # the judge's limits after rounding (pointing.py rule 4): each axis by its own box
        whole_degrees=az.whole_degrees,
        steps_deg=az.steps_deg,
        tenths=az.tenths,
        cuts_down=az.cuts_down,
        el_rounding=(el.whole_degrees, el.tenths, el.cuts_down, el.steps_deg),
        hamlib_rot_type=HamlibRotType.AZEL,
    )
