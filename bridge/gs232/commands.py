"""GS-232B and Easycomm II sessions onto one Rotator: each client's lines judged by
Rotator.submit and answered in the protocol's bytes (package rules 4-7); the servers that carry
them are the shared line server (tcplines.py) and the pty server (ptylines.py).

The Rotator is a Protocol: the bridge's own (engine/rotator.py) or the remote's, which stands
for the station's (remote/rotator.py), as rotctld's commands take either. Every command carries
who sent it (``Origin``: the audit trail, the control lease): on a TCP port the client's address
(``gs232 192.168.1.20``); a pty has no peer, so its commands are the interface's alone."""

from __future__ import annotations

import logging
from abc import ABC, abstractmethod
from typing import TYPE_CHECKING

from bridge.errors import Refused
from bridge.front import FrontRotator
from bridge.gs232.parser import (
    EasycommRequest,
    Gs232Kind,
    Gs232Request,
    LineSplitter,
    parse_easycomm,
    parse_gs232,
)
from bridge.model import Origin, Park, Source, Stop, Target
from bridge.tcplines import LineServer

if TYPE_CHECKING:
    from bridge.ptylines import PtyLineServer


# what these commands use of a rotator: the bridge's own or the remote's (front.py)
Rotator = FrontRotator

log = logging.getLogger(__name__)

GS232_ERROR = b"?>\r\n"  # the GS-232 error prompt; Hamlib reads a line up to LF
IDLE_TIMEOUT_S = 300.0
_STOPS = (Gs232Kind.STOP, Gs232Kind.STOP_AZ, Gs232Kind.STOP_EL)


def _position(rotator: Rotator) -> tuple[float, float] | None:
    """The true bearing and elevation now (0 without an elevation axis), None when the bridge
    does not currently have them: never the last value seen (rotctld's rule 5)."""
    status = rotator.status
    el = status.elevation_deg if rotator.spec.has_elevation else 0.0
    az = status.bearing_deg
    if not rotator.spec.can_report_position or not status.available or az is None or el is None:
        return None
    return az, el


def _azimuth(az_deg: float) -> str:
    whole = round(az_deg)
    return f"{whole + 360 if whole < 0 else whole:03d}"  # a GS-232 azimuth is never negative


class _Session(ABC):
    """One client's lines (tcplines.LineSession): each answered in turn, a failure contained
    (rule 8 of the house: answered with the protocol's error, logged)."""

    name = ""
    failed_reply = b""
    source = Source.GS232

    def __init__(self, rotator: Rotator, peer: str | None = None) -> None:
        self.rotator = rotator
        self.origin = Origin(self.source, None, peer)  # peer: the TCP client's address
        self._lines = LineSplitter()

    @property
    def idle(self) -> bool:
        return self._lines.idle

    def feed(self, data: bytes) -> list[bytes]:
        out = []
        for line in self._lines.feed(data):
            try:
                out.append(self.answer(line))
            except Exception:
                log.exception("%s for %s: %r failed", self.name, self.rotator.id, line)
                out.append(self.failed_reply)
        return out

    @abstractmethod
    def answer(self, line: str | None) -> bytes:
        """The protocol's reply to one line (b"" for none)."""


class Gs232Session(_Session):
    """One GS-232B client."""

    name, failed_reply = "gs232", GS232_ERROR

    def answer(self, line: str | None) -> bytes:
        return self.execute(line, parse_gs232(line))

    def execute(self, line: str | None, req: Gs232Request) -> bytes:
        described = f"gs232 {line}"
        if req.kind in _STOPS:  # the rotor stops as a whole: never less than what was asked
            try:
                self.rotator.submit(Stop(Source.GS232, self.origin), described)
            except Refused:  # the remote's, its broker away (package rule 6): reported there
                return GS232_ERROR
            return b""
        if req.kind in (Gs232Kind.READ_AZ, Gs232Kind.READ_EL, Gs232Kind.READ_AZEL):
            where = _position(self.rotator)
            if where is None:
                return GS232_ERROR
            az_text, el_text = _azimuth(where[0]), f"{round(where[1]):03d}"
            reply = {
                Gs232Kind.READ_AZ: f"AZ={az_text}",
                Gs232Kind.READ_EL: f"EL={el_text}",
                Gs232Kind.READ_AZEL: f"AZ={az_text}  EL={el_text}",
            }[req.kind]
            return reply.encode() + b"\r\n"
        if req.kind is Gs232Kind.GOTO_AZ or req.kind is Gs232Kind.GOTO_AZEL:
            el = req.el_deg
            if el == 0 and not self.rotator.spec.has_elevation:
                el = None  # Hamlib sends W with elevation 000 to an azimuth-only rotator
            try:
                target = Target(req.az_deg, el, Source.GS232, origin=self.origin)
                self.rotator.submit(target, described)
            except Refused:
                return GS232_ERROR  # Rotator.submit has reported it on R/error
            return b""
        log.debug("gs232 for %s: %r not understood", self.rotator.id, line)
        return GS232_ERROR


class EasycommSession(_Session):
    """One Easycomm II client."""

    name, failed_reply, source = "easycomm", b"ALinternal error\n", Source.EASYCOMM

    def answer(self, line: str | None) -> bytes:
        return self.execute(line, parse_easycomm(line))

    def execute(self, line: str | None, req: EasycommRequest) -> bytes:
        described = f"easycomm {line}"
        alarms: list[str] = []
        if req.invalid is not None:
            return f"ALinvalid {req.invalid}\n".encode("latin-1")
        if req.stop:  # a line that stops does nothing else
            try:
                self.rotator.submit(Stop(Source.EASYCOMM, self.origin), described)
            except Refused as exc:  # the remote's, its broker away (package rule 6)
                alarms.append(f"refused {exc.code.value}")
        elif req.park:
            try:
                self.rotator.submit(Park(source=Source.EASYCOMM, origin=self.origin), described)
            except Refused as exc:
                alarms.append(f"refused {exc.code.value}")
        elif req.az_deg is not None or req.el_deg is not None:
            el = req.el_deg
            if el == 0 and not self.rotator.spec.has_elevation:
                el = None  # Hamlib sends EL0.0 to an azimuth-only rotator
            try:
                target = Target(req.az_deg, el, Source.EASYCOMM, origin=self.origin)
                self.rotator.submit(target, described)
            except Refused as exc:
                alarms.append(f"refused {exc.code.value}")
        alarms += [f"{word} not available" for word in req.unsupported]
        words = self._answers(req.queries)
        if words is None:
            alarms.append("position unknown")
            words = []
        lines = [" ".join(words)] if words else []
        lines += ["AL" + alarm for alarm in alarms]
        return "".join(text + "\n" for text in lines).encode("ascii", "replace")

    def _answers(self, queries: tuple[str, ...]) -> list[str] | None:
        words = []
        where = _position(self.rotator) if set(queries) & {"AZ", "EL"} else None
        for query in queries:
            if query == "VE":
                words.append("VErotor-bridge")
            elif where is None:
                return None
            else:
                words.append(f"AZ{where[0]:.1f}" if query == "AZ" else f"EL{where[1]:.1f}")
        return words


def gs232_server(rotator: Rotator, port: int, bind: str = "127.0.0.1") -> LineServer:
    """The GS-232B port of one rotator."""
    return LineServer(
        rotator.id,
        port,
        bind,
        lambda: Gs232Session(rotator),
        label="gs232",
        peer_session=lambda peer: Gs232Session(rotator, peer),
        key="gs232",
        idle_timeout_s=IDLE_TIMEOUT_S,
    )


def easycomm_server(rotator: Rotator, port: int, bind: str = "127.0.0.1") -> LineServer:
    """The Easycomm II port of one rotator."""
    return LineServer(
        rotator.id,
        port,
        bind,
        lambda: EasycommSession(rotator),
        label="easycomm",
        peer_session=lambda peer: EasycommSession(rotator, peer),
        key="easycomm",
        idle_timeout_s=IDLE_TIMEOUT_S,
    )


def gs232_pty(rotator: Rotator, path: str) -> PtyLineServer:
    """The GS-232B pty of one rotator, linked at ``path``."""
    from bridge.ptylines import PtyLineServer  # package rule 8

    return PtyLineServer(
        rotator.id, path, lambda: Gs232Session(rotator), label="gs232", key="gs232"
    )


def easycomm_pty(rotator: Rotator, path: str) -> PtyLineServer:
    """The Easycomm II pty of one rotator, linked at ``path``."""
    from bridge.ptylines import PtyLineServer  # package rule 8

    return PtyLineServer(
        rotator.id, path, lambda: EasycommSession(rotator), label="easycomm", key="easycomm"
    )
