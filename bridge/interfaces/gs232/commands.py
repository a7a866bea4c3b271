"""GS-232A/B, Easycomm II and DCU-1 sessions onto one Rotator: each client's commands judged by
Rotator.submit and answered in the protocol's bytes (package rules 4-7, 9, 10); the servers that
carry them are the shared line server (interfaces/tcplines.py) and the pty server
(interfaces/ptylines.py), made from one table, EMULATIONS (package rule 11).

The Rotator is a Protocol: the bridge's own (runtime/rotator.py) or the remote's, which stands
for the station's (remote/rotator.py), as rotctld's commands take either. Every command carries
who sent it (``Origin``: the audit trail, the control lease): on a TCP port the client's address
(``gs232 192.168.1.20``); a pty has no peer, so its commands are the interface's alone."""

from __future__ import annotations

import logging
import math
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Generic, Protocol, TypeVar

from bridge.core.errors import Refused
from bridge.core.model import Origin, Park, Source, Stop, Target
from bridge.front import FrontRotator, HaltCounted
from bridge.interfaces.gs232.parser import (
    DCU1_HARMLESS,
    Dcu1Kind,
    Dcu1Reader,
    Dcu1Request,
    EasycommRequest,
    Gs232Kind,
    Gs232Request,
    LineSplitter,
    dcu1_holds_stop,
    easycomm_holds_stop,
    gs232_holds_stop,
    parse_easycomm,
    parse_gs232,
)
from bridge.interfaces.tcplines import (
    LINE_ENDS,
    Fence,
    LineServer,
    LineSession,
    halt_count,
    halt_watchers,
)
from bridge.pointing import unfolded

if TYPE_CHECKING:
    from bridge.interfaces.ptylines import PtyLineServer
    from bridge.pointing import Pointing


# what these commands use of a rotator: the bridge's own or the remote's (front.py)
Rotator = FrontRotator

log = logging.getLogger(__name__)

GS232_ERROR = b"?>\r\n"  # the GS-232 error prompt; Hamlib reads a line up to LF
# what a Rotor-EZ prints after an invalid command (and for V): the one text it is known to send
DCU1_ERROR = b"C2000 IDIOM V1.4S "
DCU1_STORED_S = 1.0  # package rule 10: a bearing AP1 stored is for an AM1 within this
IDLE_TIMEOUT_S = 300.0
_STOPS = (Gs232Kind.STOP, Gs232Kind.STOP_AZ, Gs232Kind.STOP_EL)
Item = TypeVar("Item")


def _position(
    rotator: Rotator,
    pointing: Pointing | None = None,
    *,
    at_360: Callable[[float], bool] | None = None,
) -> tuple[float, float] | None:
    """The true bearing and elevation now (0 without an elevation axis), None when the bridge
    does not currently have them: never the last value seen (rotctld's rule 5). With the
    rotator's ``pointing`` (a client that named the side, package rule 4), the true bearing
    unfolded past 360 on a rotor that does not wrap, as rotctld's ``p`` answers such a client.
    With ``at_360`` (the rotator's ``Pointing.at_360``, asked only of a raw reading of the
    true bearing 0), the clockwise end of a scale that wraps is 360, not 0 (package rule 4)."""
    status = rotator.status
    el = status.elevation_deg if rotator.spec.has_elevation else 0.0
    az = status.bearing_deg
    if pointing is not None and not pointing.az_wraps and status.raw_bearing_deg is not None:
        az = unfolded(az, status.raw_bearing_deg)
    elif (
        at_360 is not None
        and az == 0.0
        and status.raw_bearing_deg
        and at_360(status.raw_bearing_deg)
    ):
        az = 360.0
    if not rotator.spec.can_report_position or not status.available or az is None or el is None:
        return None
    return az, el


def _azimuth(az_deg: float) -> str:
    whole = round(az_deg)
    return f"{whole + 360 if whole < 0 else whole:03d}"  # a GS-232 azimuth is never negative


class _Reader(Protocol[Item]):
    """A protocol's input, sans-IO: bytes in, its commands (or lines) out."""

    @property
    def idle(self) -> bool: ...

    def feed(self, data: bytes) -> list[Item]: ...


class _Session(ABC, Generic[Item]):
    """One client's commands (tcplines.LineSession): each answered in turn, a failure contained
    (rule 8 of the house: answered with the protocol's error, logged)."""

    name = ""
    failed_reply = b""
    source = Source.GS232

    def __init__(self, rotator: Rotator, peer: str | None = None) -> None:
        self.rotator = rotator
        self.origin = Origin(self.source, None, peer)  # peer: the TCP client's address
        self._reader = self.reader()
        self.fence = Fence(rotator)  # tcplines.py rule 9: when its bytes came

    @abstractmethod
    def reader(self) -> _Reader[Item]:
        """A fresh reader of the protocol's input."""

    @property
    def idle(self) -> bool:
        return self._reader.idle

    def feed(self, data: bytes) -> list[bytes]:
        out = []
        for item in self._reader.feed(data):
            try:
                out.append(self.answer(item))
            except Exception:
                log.exception("%s for %s: %r failed", self.name, self.rotator.id, item)
                out.append(self.failed_reply)
        return out

    @abstractmethod
    def answer(self, item: Item) -> bytes:
        """The protocol's reply to one command (b"" for none)."""

    def _not_carried_out(self, why: str, described: str) -> None:
        """Package rule 12: a line that is no command the bridge carries out is said on
        R/error and in the log (rate-limited there), besides the protocol's answer: the
        client's user sees why nothing moved (an attack pass: ``M180.5`` and ``AZnan`` were
        answered on the wire alone, and logged at debug). Not in the audit trail, which is
        not rate-limited: it is no command (a review: a client's junk lines would have rotated
        the commands out of its file)."""
        self.rotator.report_refusal(why, described)


class _LineSession(_Session[str | None]):
    """A protocol whose commands are lines (LineSplitter)."""

    def reader(self) -> LineSplitter:
        return LineSplitter()


class Gs232Rotator(FrontRotator, Protocol):
    """What the GS-232 session asks of a rotator besides a front end's: its pointing (the
    offset and whether its azimuth wraps), for a client that named the side (package rule 4)."""

    @property
    def pointing(self) -> Pointing: ...


class _SidedSession(_LineSession):
    """A client that reads the bearing unfolded past 360 while ``names_side``: its last
    accepted azimuth was past 360 (package rule 4)."""

    rotator: Gs232Rotator

    def __init__(self, rotator: Rotator, peer: str | None = None) -> None:
        super().__init__(rotator, peer)
        self.names_side = False

    def _where(self) -> tuple[float, float] | None:
        """The position this client reads (package rule 4)."""
        pointing = self.rotator.pointing if self.names_side else None
        return _position(self.rotator, pointing, at_360=self._at_360)

    def _at_360(self, raw_deg: float) -> bool:
        return self.rotator.pointing.at_360(raw_deg)


class Gs232Session(_SidedSession):
    """One GS-232 client; ``replies`` "A" or "B": the controller whose readings it gives
    (package rule 2)."""

    name, failed_reply = "gs232", GS232_ERROR

    def __init__(self, rotator: Rotator, peer: str | None = None, *, replies: str = "B") -> None:
        super().__init__(rotator, peer)
        if replies not in ("A", "B"):
            raise ValueError(f"GS-232 replies are A or B, not {replies!r}")
        self.replies = replies

    def answer(self, line: str | None) -> bytes:
        return self.execute(line, parse_gs232(line))

    def execute(self, line: str | None, req: Gs232Request) -> bytes:
        described = f"gs232 {line}"
        if req.kind in _STOPS:  # the rotor stops as a whole: never less than what was asked
            stop = Stop(Source.GS232, self.origin)
            try:
                self.fence.halting(lambda: self.fence.submit(stop, described))
            except Refused:  # the remote's, its broker away (package rule 6): reported there
                return GS232_ERROR
            return b""
        if req.kind in (Gs232Kind.READ_AZ, Gs232Kind.READ_EL, Gs232Kind.READ_AZEL):
            where = self._where()
            if where is None:
                return GS232_ERROR
            az_text, el_text = _azimuth(where[0]), f"{round(where[1]):03d}"
            if self.replies == "A":
                az_text, el_text = f"+0{az_text}", f"+0{el_text}"
                reply = {
                    Gs232Kind.READ_AZ: az_text,
                    Gs232Kind.READ_EL: el_text,
                    Gs232Kind.READ_AZEL: az_text + el_text,
                }[req.kind]
            else:
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
                self.fence.move(target, described)
            except Refused:
                return GS232_ERROR  # Rotator.submit has reported it on R/error
            self.names_side = req.az_deg is not None and not 0 <= req.az_deg <= 360  # rule 4
            return b""
        log.debug("gs232 for %s: %r not understood", self.rotator.id, line)
        if line is None:
            self._not_carried_out("a line too long to be a GS-232 command", "gs232 (long line)")
        else:
            why = f"{line!r} is no GS-232 command the bridge carries out"
            self._not_carried_out(why, described)
        return GS232_ERROR


class EasycommSession(_SidedSession):
    """One Easycomm II client."""

    name, failed_reply, source = "easycomm", b"ALinternal error\n", Source.EASYCOMM

    def answer(self, line: str | None) -> bytes:
        req = parse_easycomm(line)
        try:
            return self.execute(line, req)
        except Exception:  # package rule 3: a line that asked nothing is answered with nothing
            if req.queries:
                raise  # (feed logs it and answers ``failed_reply``)
            log.exception("%s for %s: %r failed", self.name, self.rotator.id, line)
            return b""

    def execute(self, line: str | None, req: EasycommRequest) -> bytes:
        described = f"easycomm {line}"
        if req.stop:  # a line that stops does nothing else, and a malformed word beside it
            # keeps it from nothing (package rules 3 and 6)
            stop = Stop(Source.EASYCOMM, self.origin)
            try:
                self.fence.halting(lambda: self.fence.submit(stop, described))
            except Refused:  # the remote's, its broker away (package rule 6): reported there
                pass
        if req.invalid is not None:  # nothing else runs (package rule 3)
            self._not_carried_out(f"Easycomm: invalid {req.invalid}", described)  # rule 12
            # package rule 3: a line that asked nothing is answered with nothing
            return f"ALinvalid {req.invalid}\n".encode("latin-1") if req.queries else b""
        if req.park and not req.stop:
            try:
                self.fence.move(Park(source=Source.EASYCOMM, origin=self.origin), described)
            except Refused:  # Rotator.submit has reported it on R/error
                pass
        elif not req.stop and (req.az_deg is not None or req.el_deg is not None):
            el = req.el_deg
            if el == 0 and not self.rotator.spec.has_elevation:
                el = None  # Hamlib sends EL0.0 to an azimuth-only rotator
            try:
                target = Target(req.az_deg, el, Source.EASYCOMM, origin=self.origin)
                self.fence.move(target, described)
            except Refused:  # Rotator.submit has reported it on R/error
                pass
            else:  # rule 4 (an elevation alone keeps the azimuth, and its side)
                if req.az_deg is not None:
                    self.names_side = not 0 <= req.az_deg <= 360
        if req.unsupported:  # rule 12 (a garbled poll's AZ ML reads as a jog asked)
            asked = ", ".join(req.unsupported)
            self._not_carried_out(f"Easycomm: {asked} not carried out by the bridge", described)
        if not req.queries:  # package rule 3: Hamlib reads no reply to a line that asks
            return b""  # nothing; what was refused is on R/error (Rotator.submit, rule 12)
        words = self._answers(req.queries)
        line = "ALposition unknown" if words is None else " ".join(words)
        return (line + "\n").encode("ascii", "replace")

    def _answers(self, queries: tuple[str, ...]) -> list[str] | None:
        words = []
        where = self._where() if set(queries) & {"AZ", "EL"} else None  # (rule 4)
        for query in queries:
            if query == "VE":
                words.append("VErotor-bridge")
            elif where is None:
                return None
            else:
                words.append(f"AZ{where[0]:.1f}" if query == "AZ" else f"EL{where[1]:.1f}")
        return words


class Dcu1Rotator(HaltCounted, Protocol):
    """What the DCU-1 session asks of a rotator besides a front end's (package rule 10): its
    halts counted for ``since`` (front.py rule 3)."""


class Dcu1Session(_Session[Dcu1Request]):
    """One DCU-1 / Rotor-EZ client (package rules 9 and 10). ``clock``: when AP1 stored its
    bearing (monotonic seconds)."""

    rotator: Dcu1Rotator

    name, failed_reply, source = "dcu1", DCU1_ERROR, Source.DCU1

    def __init__(
        self,
        rotator: Dcu1Rotator,
        peer: str | None = None,
        *,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        super().__init__(rotator, peer)
        self._clock = clock
        # AP1's bearing, when, the halts when its bytes came (None: a halt not its own came
        # after them, before it was read), and the count its move hands to submit (since)
        self._stored: tuple[int, float, int | None, int] | None = None

    def reader(self) -> Dcu1Reader:
        return Dcu1Reader()

    def answer(self, item: Dcu1Request) -> bytes:
        described = f"dcu1 {item.text}"
        if item.kind is Dcu1Kind.STOP or item.stops:  # first, whatever else the frame was
            stop = Stop(Source.DCU1, self.origin)
            try:
                self.fence.halting(lambda: self.fence.submit(stop, described))
            except Refused:  # the remote's, its broker away (package rule 6): reported there
                return DCU1_ERROR
            if item.kind is Dcu1Kind.STOP:
                return b""
        if item.kind is Dcu1Kind.READ:
            where = _position(self.rotator)
            if where is None:  # package rule 10: silence, a timeout to the client
                log.debug("dcu1 for %s: %r, position unknown", self.rotator.id, item.text)
                return b""
            return b";%03d" % (math.floor(where[0] + 0.5) % 360)
        if item.kind is Dcu1Kind.STORE:
            assert item.az_deg is not None
            rotator = self.rotator
            # package rule 10: the halts when its bytes came (the look that held them,
            # tcplines.py rule 9), not when it is read: a halt counted between the two,
            # not this client's own, overtook it (None: an AM1 will not turn to it)
            halts = None if self.fence.overtaken() else rotator.halts
            self._stored = (
                item.az_deg,
                self._clock(),
                halts,
                rotator.halts_for(Source.DCU1),
            )
            return b""
        if item.kind is Dcu1Kind.EXECUTE or item.kind is Dcu1Kind.GOTO:
            return self._turn(item, described)
        if item.kind is Dcu1Kind.OPTION:
            return b""  # the station's options are its own (R/option): taken, changed nothing
        if item.kind is Dcu1Kind.VERSION:
            return DCU1_ERROR  # the banner names the version
        log.debug("dcu1 for %s: %r not understood", self.rotator.id, item.text)
        self._not_carried_out(f"{item.text!r} is no DCU-1 command", described)  # rule 12
        return DCU1_ERROR

    def _turn(self, item: Dcu1Request, described: str) -> bytes:
        az_deg, since = item.az_deg, None
        if item.kind is Dcu1Kind.EXECUTE:  # the bearing AP1 stored, once, while fresh
            stored, self._stored = self._stored, None
            if stored is None or self._clock() - stored[1] > DCU1_STORED_S:
                why = f"AM1; with no bearing stored by AP1 in the last {DCU1_STORED_S:g} s"
                self.rotator.report_refusal(why, described, origin=self.origin)
                return DCU1_ERROR
            if stored[2] is None or self.rotator.halts != stored[2]:  # rule 10: a STOP came
                # after it (stored[2] None: before it was read, a client paused over its budget)
                why = "AM1; after a STOP or lock ON that came after the AP1's bearing"
                self.rotator.report_refusal(why, described, origin=self.origin)
                return DCU1_ERROR
            # a STOP between the check above and the put overtakes the bearing: mailbox.py
            az_deg, since = stored[0], stored[3]  # rule 10 (a review: it went out after it)
        try:
            # package rule 10: 000 is north, a direction, not an end of the travel (the
            # protocol cannot say 360, Hamlib sends 360 as AP1000;): the end nearer the rotor
            # (pointing.py rule 2; an attack pass: a Yaesu behind a GS-232 at 355 asked for
            # north was sent M000 and turned back through south)
            either = az_deg is not None and az_deg % 360 == 0
            target = Target(az_deg, None, Source.DCU1, origin=self.origin, az_either_end=either)
            self.fence.move(target, described, since=since)
        except Refused:
            return DCU1_ERROR  # Rotator.submit has reported it on R/error
        return b""


@dataclass(frozen=True)
class Emulation:
    """A controller's protocol offered to programs (package rule 11): ``key`` is its settings'
    prefix (``gs232_port``, ``gs232_bind``, ``gs232_pty``), ``ends`` what ends its commands."""

    key: str
    session: Callable[..., LineSession]  # (rotator, peer, **options)
    halts: Callable[[bytes], bool]  # whether complete commands hold a stop (tcplines rule 5)
    ends: bytes = LINE_ENDS
    options: tuple[str, ...] = ()  # each session's keyword, from the setting <key>_<option>
    singles: bytes = b""  # whole commands of one byte that move nothing (tcplines rule 2)

    def options_of(self, table: object) -> dict[str, str]:
        """Its options as a settings table gives them (``gs232_replies``: replies)."""
        return {name: getattr(table, f"{self.key}_{name}") for name in self.options}

    def offered(self, rotator: Rotator, table: object) -> list[LineServer | PtyLineServer]:
        """The port and the pty a settings table (a station's ``[[rotators]]``, a remote's
        ``[[endpoints]]``) asks for with ``<key>_port``, ``<key>_bind`` and ``<key>_pty``."""
        options = self.options_of(table)
        out: list[LineServer | PtyLineServer] = []
        if (port := getattr(table, f"{self.key}_port")) is not None:
            out.append(self.server(rotator, port, getattr(table, f"{self.key}_bind"), **options))
        if (path := getattr(table, f"{self.key}_pty")) is not None:
            out.append(self.pty(rotator, path, **options))
        return out

    def server(
        self, rotator: Rotator, port: int, bind: str = "127.0.0.1", **options: str
    ) -> LineServer:
        """Its TCP port for one rotator; ``options`` go to each session (gs232's replies)."""
        return LineServer(
            rotator.id,
            port,
            bind,
            lambda: self.session(rotator, None, **options),
            label=self.key,
            peer_session=lambda peer: self.session(rotator, peer, **options),
            key=self.key,
            idle_timeout_s=IDLE_TIMEOUT_S,
            ends=self.ends,
            halts=self.halts,
            singles=self.singles,
            halt_count=halt_count(rotator),
            halt_watchers=halt_watchers(rotator),
        )

    def pty(self, rotator: Rotator, path: str, **options: str) -> PtyLineServer:
        """Its pty for one rotator, linked at ``path``."""
        from bridge.interfaces.ptylines import PtyLineServer  # package rule 8

        return PtyLineServer(
            rotator.id,
            path,
            lambda: self.session(rotator, None, **options),
            label=self.key,
            key=self.key,
            halt_count=halt_count(rotator),
            halt_watchers=halt_watchers(rotator),
        )


EMULATIONS = {
    e.key: e
    for e in (
        Emulation("gs232", Gs232Session, gs232_holds_stop, options=("replies",)),
        Emulation("easycomm", EasycommSession, easycomm_holds_stop),
        Emulation("dcu1", Dcu1Session, dcu1_holds_stop, ends=b"\r\n;", singles=DCU1_HARMLESS),
    )
}


def gs232_server(rotator: Rotator, port: int, bind: str = "127.0.0.1") -> LineServer:
    """The GS-232B port of one rotator."""
    return EMULATIONS["gs232"].server(rotator, port, bind)


def easycomm_server(rotator: Rotator, port: int, bind: str = "127.0.0.1") -> LineServer:
    """The Easycomm II port of one rotator."""
    return EMULATIONS["easycomm"].server(rotator, port, bind)


def gs232_pty(rotator: Rotator, path: str) -> PtyLineServer:
    """The GS-232B pty of one rotator, linked at ``path``."""
    return EMULATIONS["gs232"].pty(rotator, path)


def easycomm_pty(rotator: Rotator, path: str) -> PtyLineServer:
    """The Easycomm II pty of one rotator, linked at ``path``."""
    return EMULATIONS["easycomm"].pty(rotator, path)
