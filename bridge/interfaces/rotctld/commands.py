"""rotctld's commands against one Rotator: what each answers, byte for byte (rules 4-6)."""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable
from typing import TYPE_CHECKING, Protocol

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import Origin, Source, Stop, Target
from bridge.front import FrontRotator
from bridge.interfaces.rotctld.parser import Request
from bridge.interfaces.tcplines import Fence
from bridge.pointing import unfolded
from bridge.protocols.base import HamlibRotType

if TYPE_CHECKING:
    from bridge.pointing import Limits, Pointing


class Rotator(FrontRotator, Protocol):
    """What rotctld's commands use of a rotator: the bridge's own (runtime/rotator.py) or the
    remote's, which stands for the station's (remote/rotator.py)."""

    @property
    def pointing(self) -> Pointing: ...
    @property
    def limits(self) -> Limits: ...


log = logging.getLogger(__name__)


# Hamlib error codes (rig.h, enum rig_errcode_e), sent negated as "RPRT -n".
RIG_OK = 0
RIG_EINVAL = 1  # invalid parameter: out of range, not a number
RIG_ETIMEOUT = 5  # the controller does not answer (port open, no valid reply)
RIG_EIO = 6  # the serial link is down (port closed or gone)
RIG_EINTERNAL = 7
RIG_ERJCTED = 9  # command rejected: the safety lock is ON, or a keep-out sector
RIG_ENAVAIL = 11  # the model cannot do this

# how dump_caps spells a rot_type (Hamlib's dumpcaps_rot.c)
_CAPS_ROT_TYPE = {
    HamlibRotType.AZ: "Azimuth",
    HamlibRotType.EL: "Elevation",
    HamlibRotType.AZEL: "Az-El",
    HamlibRotType.OTHER: "Other",
}

_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
# what rotctld's sscanf("%d") takes as a number: a leading integer ("8x" is 8)
_LEADING_INTEGER = re.compile(r"[+-]?\d")
_DIRECTIONS = frozenset({"LEFT", "CCW", "RIGHT", "CW", "UP", "DOWN"})  # move's names, as rotctld


class RotctldCommands:
    """Executes requests against one rotator and renders rotctld's reply bytes."""

    def __init__(self, rotator: Rotator, origin: Origin | None = None) -> None:
        self.rotator = rotator
        self._origin = origin  # who this client is (the audit trail, the control lease)
        self.fence = Fence(rotator)  # tcplines.py rule 9
        # Hamlib's facts about the model are on its spec (protocols/)
        spec = rotator.spec
        self.hamlib_model = spec.hamlib_model
        self.rot_type = spec.hamlib_rot_type
        # rotctld prints a backend without get_info as "None"
        self.info = "None" if spec.hamlib_info is None else spec.hamlib_info
        # this client's last accepted P named the side (outside 0..360, on a rotor that can pass
        # 360): p then answers past 360 too, else in 0..360 like Hamlib's own backends
        self.names_side = False

    def execute(self, request: Request) -> bytes:
        handler = getattr(self, "_" + request.command.name, self._not_available)
        try:
            code, body = handler(request)
        except Exception:
            log.exception("rotctld: %s failed", request.command.name)
            code, body = -RIG_EINTERNAL, ""
        return _frame(request, code, body).encode()

    # -- commands: each returns (code, body); body is rendered for the request's protocol ------

    def _get_pos(self, req: Request) -> tuple[int, str]:
        spec = self.rotator.spec
        if not spec.can_report_position:
            return -RIG_ENAVAIL, ""
        status, aim = self.rotator.status, self.rotator.pointing
        az = status.bearing_deg
        if self.names_side and not aim.az_wraps and status.raw_bearing_deg is not None:
            # a client that sent P 400 reads 400 back (in the range \dump_state gives): the true
            # bearing unfolded, as P takes it (pointing.py rule 2); one that sent P 40 reads 40
            # even where the bridge took it on to raw 400, the shorter way
            az = unfolded(az, status.raw_bearing_deg)
        elif az == 0.0 and aim.at_360(status.raw_bearing_deg) and not spec.hamlib_folds_360:
            # the clockwise end of a scale that wraps reads 360.00, as Hamlib's GS-232 or
            # Easycomm backend reads it and as P takes it (pointing.py rule 2: P 360 is that
            # end, P 0 the other): 0.00 named the other end, a whole turn back
            az = 360.0
        el = status.elevation_deg if spec.has_elevation else 0.0
        if not status.available or az is None or el is None:
            return _link_code(status.connected), ""
        return RIG_OK, _values(req, [("Azimuth", f"{az:.2f}"), ("Elevation", f"{el:.2f}")])

    def _set_pos(self, req: Request) -> tuple[int, str]:
        az, el = (_number(a) for a in req.args)
        if az is None or el is None:  # package rule 6: said on R/error too
            why = f"P {' '.join(req.args)!r}: the azimuth and elevation are no numbers"
            self.rotator.report_refusal(why, _describe(req))  # (no audit: gs232 rule 12)
            return -RIG_EINVAL, ""
        el_deg = el if self.rotator.spec.has_elevation or el != 0 else None
        code, body = self._submit_target(az, el_deg, req)
        if code == RIG_OK:
            self.names_side = not 0.0 <= az <= 360.0
        return code, body

    def _park(self, req: Request) -> tuple[int, str]:
        park = self.rotator.pointing.park  # the same park as MQTT's and Home Assistant's
        if park is None:
            return -RIG_ENAVAIL, ""
        return self._submit_target(park[0], park[1], req, park=True)

    def _stop(self, req: Request) -> tuple[int, str]:
        stop = Stop(Source.ROTCTLD, self._origin)
        try:
            self.fence.halting(lambda: self.fence.submit(stop, _describe(req)))
        except Refused as exc:  # the station's own never refuses a stop; the remote's (remote/)
            return _refusal_code(exc, self.rotator.status.connected), ""  # can't deliver one
        return RIG_OK, ""

    def _move(self, req: Request) -> tuple[int, str]:
        direction, speed = req.args
        if not (direction in _DIRECTIONS or _LEADING_INTEGER.match(direction)):
            return -RIG_EINVAL, ""
        if not _LEADING_INTEGER.match(speed):
            return -RIG_EINVAL, ""
        return -RIG_ENAVAIL, ""  # no supported model moves by direction and speed yet

    def _reset(self, req: Request) -> tuple[int, str]:
        if not _LEADING_INTEGER.match(req.args[0]):
            return -RIG_EINVAL, ""
        return -RIG_ENAVAIL, ""

    def _set_conf(self, req: Request) -> tuple[int, str]:
        return -RIG_ENAVAIL, ""

    def _not_available(self, req: Request) -> tuple[int, str]:
        """Package rule 3: a command of rotctld's the bridge does not carry out (levels,
        functions, parameters, send_cmd, the locator and great-circle helpers, pause)."""
        return -RIG_ENAVAIL, ""

    def _get_status(self, req: Request) -> tuple[int, str]:
        return -RIG_ENAVAIL, ""

    def _get_info(self, req: Request) -> tuple[int, str]:
        return RIG_OK, _values(req, [("Info", self.info)])

    def _dump_state(self, req: Request) -> tuple[int, str]:
        lim, aim = self.rotator.limits, self.rotator.pointing
        az_min, az_max = aim.target_range()  # the range of targets in true bearings
        # south_zero stays 0 whatever the offset: Hamlib's client adds 180 to every P it sends
        # and every p it reads when it is 1, and P and p here are true bearings already
        south = 0
        lines = [
            ("rotctld Protocol Ver: 1", "1"),
            (f"Rotor Model: {self.hamlib_model}", str(self.hamlib_model)),
            (f"Minimum Azimuth: {az_min:f}", f"min_az={az_min:f}"),
            (f"Maximum Azimuth: {az_max:f}", f"max_az={az_max:f}"),
            (f"Minimum Elevation: {lim.el_min_deg:f}", f"min_el={lim.el_min_deg:f}"),
            (f"Maximum Elevation: {lim.el_max_deg:f}", f"max_el={lim.el_max_deg:f}"),
            (f"South Zero: {south}", f"south_zero={south}"),
            (f"rot_type={self.rot_type}", f"rot_type={self.rot_type}"),
            ("done", "done"),
        ]
        if req.extended:
            return RIG_OK, "".join(labelled + req.sep for labelled, _ in lines)
        return RIG_OK, "".join(terse + "\n" for _, terse in lines)

    def _dump_caps(self, req: Request) -> tuple[int, str]:
        spec, lim = self.rotator.spec, self.rotator.limits

        def yn(flag: bool) -> str:
            return "Y" if flag else "N"

        rot_type = _CAPS_ROT_TYPE[self.rot_type]
        return RIG_OK, (
            f"Caps dump for model:\t{self.hamlib_model}\n"
            f"Model name:\t\t{spec.display_name}\n"
            f"Mfg name:\t\t{spec.manufacturer}\n"
            "Backend version:\trotor-bridge\n"
            "Backend status:\t\tStable\n"
            f"Rot type:\t\t{rot_type}\n"
            "Port type:\t\tNetwork link (rotor-bridge)\n"
            f"Min Azimuth:\t\t{lim.az_min_deg:.2f}\n"
            f"Max Azimuth:\t\t{lim.az_max_deg:.2f}\n"
            f"Min Elevation:\t\t{lim.el_min_deg:.2f}\n"
            f"Max Elevation:\t\t{lim.el_max_deg:.2f}\n"
            "Can set Position:\tY\n"
            f"Can get Position:\t{yn(spec.can_report_position)}\n"
            "Can Stop:\t\tY\n"
            f"Can Park:\t\t{yn(self.rotator.pointing.park is not None)}\n"
            "Can Reset:\t\tN\n"
            "Can Move:\t\tN\n"
            f"Can get Info:\t\t{yn(spec.hamlib_info is not None)}\n"
            "Can get Status:\t\tN\n"
            "\nOverall backend warnings: 0\n"
        )

    def _submit_target(
        self, az: float, el: float | None, req: Request, *, park: bool = False
    ) -> tuple[int, str]:
        """``az`` is a true bearing (Gpredict and loggers think in true bearings): pointing.py."""
        try:
            target = Target(az, el, Source.ROTCTLD, park=park, origin=self._origin)
            self.fence.move(target, _describe(req))  # tcplines.py rule 9
        except Refused as exc:
            return _refusal_code(exc, self.rotator.status.connected), ""
        return RIG_OK, ""


def _refusal_code(exc: Refused, connected: bool) -> int:
    if exc.code in (RefusalCode.LIMITS, RefusalCode.UNSUPPORTED):  # e.g. elevation on az-only
        return -RIG_EINVAL
    if exc.code is RefusalCode.OFFLINE:
        return _link_code(connected)
    return -RIG_ERJCTED  # locked, invalid: the bridge said no


def _link_code(connected: bool) -> int:
    # what rotctld itself answers: a vanished port is an I/O error, a silent controller a timeout
    return -RIG_ETIMEOUT if connected else -RIG_EIO


def _number(text: str) -> float | None:
    text = text.replace(",", ".")  # rotctld accepts a decimal comma ("P 10,5 20")
    return float(text) if _NUMBER.fullmatch(text) else None


def _values(req: Request, pairs: Iterable[tuple[str, str]]) -> str:
    if req.extended:
        return "".join(f"{label}: {value}{req.sep}" for label, value in pairs)
    return "".join(f"{value}\n" for _, value in pairs)


def _frame(req: Request, code: int, body: str) -> str:
    if req.extended:
        head = req.command.name + ":" + "".join(" " + a for a in req.args) + req.sep
        return head + (body if code == RIG_OK else "") + f"RPRT {code}\n"
    if code != RIG_OK:
        return f"RPRT {code}\n"
    return body if req.command.returns_values else body + "RPRT 0\n"


def _describe(req: Request) -> str:
    return " ".join(("rotctld", req.command.name, *req.args))
