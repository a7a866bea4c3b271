"""What a PstRotator or N1MM datagram does, once parsed (datagrams.py): the command it gives its
rotator, and the ``AZ?``/``EL?`` replies. No thread and no socket of its own: server.py reads
the datagrams on its thread and hands each here with the socket to answer from.

Rules:
1. Every command goes through the Rotator like MQTT's and rotctld's (Source.PST, Source.N1MM):
   the lock, limits, keep-out sectors and offsets are judged there, and a refusal is published
   on ``R/error`` naming the protocol. The sender gets no reply to a command: neither protocol
   has one.
2. ``AZ?``/``EL?`` are answered at once from the rotator's status, to the sender's address at
   the listen port + 1, in integer degrees with a CR: one reply per kind per datagram however
   often it asks, and no more than limiter.py lets go to that address (a sender's address can
   be anybody's: a burst, then a few a second); a reply beyond is dropped, counted
   (``replies_dropped``) and logged at most once per JUNK_LOG_S. No position, no answer (never
   a made-up one); an azimuth-only rotator does not answer ``EL?``.
3. An azimuth outside 0..360 but inside Hamlib's -180..450 is folded into 0..360 (the
   rotator's own rules pick the way round); one beyond that is refused (a mis-scaled value,
   99999, must not become 279). A logger's north names a direction, not an end of the travel:
   where 0 and 360 are the ends (a Yaesu's stop at north) it goes to the one the rotor turns
   less to (``heading``). An elevation sent to an azimuth-only rotator is ignored.
4. N1MM: a datagram for another rotor name is ignored; ``*`` is taken only when one rotator
   listens on that port (or by band: rule 5), except a stop, which stops every rotator on it;
   a stop naming several rotors stops each of them on the port, a fault behind one not keeping
   it from the next. A stop the remote's rotator says it could not deliver (its link down, the
   station's bridge not heard: remote/rotator.py rule 3) is no fault: the rotator reported it.
   ``bidirectional`` 1 turns to the heading or its reciprocal, whichever the rotor turns less
   to, along its travel (a review: nearer on the compass, a Hy-Gain rotor at 170 sent 5 took
   185, 345 degrees round through north, where 5 was 165 the other way).
   A non-zero ``offset`` is logged once and not applied (its meaning is not documented).
5. N1MM by band (``choose``, pure): a turn goes to the one rotator on the port that answers to
   its name, whatever the band: a name is the sender's own choice (N1MM's Antennas tab already
   picks the antenna for the band, or the operator turned this one by hand). A name several
   rotators share, or ``*``, is chosen by band among those of them that have ``bands``: the one
   whose bands hold the message's ``<freqband>`` (core/bands.py). A message with no band, a band
   field that is no number (the refusal quotes it), a band that is no amateur band, or one no
   rotator there is for moves nothing: the refusal is
   logged (at most once per JUNK_LOG_S, with the count since) and published on the R/error of
   each rotator it could have gone to. Where none of them has bands, it is as before: ``*``
   turns the one rotator on the port, and nothing else. Stops are not chosen by band (rule 4).
6. A name several rotators share reports one heading to N1MM (server.py rule 6): the rotator
   its last turn went to by band (``N1mmEndpoint.current``), the antenna on the radio's band,
   whether or not that rotator carried the turn out (locked, offline). Until a turn has chosen
   one, the name's heading is not reported (an attack pass: each rotator reported its own
   heading under the one name, and N1MM's rotor window jumped between the two antennas'
   headings every few seconds).
7. A datagram's words go to the judge whole (on ``R/error`` and in the audit trail): a datagram
   is at most datagrams.py's MAX_DATAGRAM bytes, and tags the bridge does not read are let
   through (an attack pass: cut at 120 characters, a datagram padded with a few such tags
   turned the rotor and was audited without its ``<AZIMUTH>``).
8. A STOP or lock ON is the last word over everything sent before it (docs/architecture.md
   rule 11), whichever interface brought it: a datagram that moves a rotator and reached the
   system before that rotator last carried out a STOP or lock ON (``last_halt_s``, from any
   interface; its arrival is the system's own stamp, server.py rule 9) is not carried out,
   read however late: refused as stale on ``R/error`` (as the console's, interfaces/web/
   commands.py rule 5). An attack pass: the loggers' thread behind a neighbour's flood, a
   logger's 300 sent before the operator's rotctld S was read after it and turned the rotor
   again. A stop is never stale; a datagram with no stamp (a system that gives none) is
   judged as before. A stop these ports carried out counts from when it reached the system
   (``Halted``), not from when it was read, while no other STOP or lock ON came after it: a
   logger's turn sent after its own STOP, both read late, was refused as sent before it.
   The arrival is known between two bounds (``Arrival``: the monotonic clock read on either
   side of the wall clock, server.py rule 9), and each side takes the bound that errs its
   safe way: a move its earliest, a stop its latest. One reading after the wall clock's made
   the arrival of a turn read as a STOP landed (another thread took the interpreter between
   the two readings) look as late as that thread's turn, and the turn went to the judge
   after the stop. The halt count is read before the look at the last halt and handed with
   the move to ``submit`` (``since``, runtime/rotator.py; mailbox.py rule 10): a STOP carried
   out between the look and the judge refuses the move too (an attack pass: the operator's
   rotctld S, carried out right after the look, and the logger's 300 turned the rotor after
   it). The stop goes to ``submit`` with its arrival's latest bound (``read_s``, front.py
   rule 3): the remote refuses a move another of its front ends saw before it (remote.py
   rule 8), and a system stamp makes that window the stamp's few microseconds, not the time
   until the stop was read.
"""

from __future__ import annotations

import logging
import math
import socket
from collections.abc import Callable, Hashable, Iterable
from dataclasses import dataclass, field
from typing import Protocol

from bridge.core import geo
from bridge.core.bands import band_of_mhz
from bridge.core.errors import Refused
from bridge.core.model import Origin, Park, Source, Stop, Target, Toward
from bridge.core.text import shown_past
from bridge.front import HaltCounted
from bridge.interfaces.loggers.datagrams import N1mmRequest, PstRequest, ascii_text, pst_reply
from bridge.interfaces.loggers.limiter import ReplyLimiter
from bridge.pointing import Pointing


class Rotator(HaltCounted, Protocol):
    """What these commands use of a rotator: the bridge's own or the remote's (front.py rule
    3): when it last carried out a STOP or lock ON (rule 8; monotonic), and its count of them
    as a move of ``source`` hands it to ``submit`` (``since``: rule 8); and its judge's terms
    (rule 4: which way it turns less)."""

    @property
    def last_halt_s(self) -> float: ...
    @property
    def pointing(self) -> Pointing: ...


log = logging.getLogger(__name__)

JUNK_LOG_S = 10.0  # malformed datagrams, replies dropped: logged at most this often, a count
STALE = "sent before a STOP or lock ON that came first: not carried out"  # rule 8
AZ_FOLDED = (-180.0, 450.0)  # Hamlib's azimuth range: folded into 0..360; beyond, refused

Fault = Callable[[str, Exception], None]  # logs a fault behind a datagram and goes on


@dataclass
class PstEndpoint:
    rotator: Rotator
    bind: str
    port: int


@dataclass(frozen=True)
class N1mmRotor:
    """A rotator on an N1MM port: the name it answers to and the bands it is for."""

    name: str
    rotator: Rotator
    bands: tuple[str, ...] = ()


@dataclass
class N1mmEndpoint:
    """One N1MM address; the rotators that answer to a name on it (several may share one,
    chosen by band: rule 5)."""

    bind: str
    port: int
    rotors: list[N1mmRotor] = field(default_factory=list)
    current: dict[str, Rotator] = field(default_factory=dict)  # rule 6: a shared name's

    def shared(self, name: str) -> bool:
        """Rule 6: several rotators here answer to ``name``."""
        return sum(r.name == name for r in self.rotors) > 1


@dataclass(frozen=True)
class NoRotor:
    """Rule 5: a turn no rotator takes. ``why`` is None for a name that is not ours (ignored);
    otherwise the refusal, reported to each of ``could``."""

    why: str | None = None
    could: tuple[N1mmRotor, ...] = ()


def choose(
    rotors: Iterable[N1mmRotor],
    name: str,
    freqband_mhz: float | None,
    freqband_unread: str | None = None,
) -> N1mmRotor | NoRotor:
    """Rule 5: the rotator a turn to ``name`` on ``freqband_mhz`` goes to, or why none does
    (``freqband_unread``: a band field given that is no number, as sent)."""
    on_port = list(rotors)
    named = [r for r in on_port if r.name == name]
    if len(named) == 1:
        return named[0]  # a name is the sender's own choice
    pool = named or (on_port if name == "*" else [])
    banded = tuple(r for r in pool if r.bands)
    if not banded:  # as before bands: "*" turns the one rotator on the port
        return pool[0] if len(pool) == 1 else NoRotor()
    if freqband_mhz is None:
        has = (
            "the message has no <freqband>"
            if freqband_unread is None
            else f"<freqband> {freqband_unread!r} is no number of MHz"
        )
        return NoRotor(f"rotor {name!r} is chosen by band, and {has}", banded)
    band = band_of_mhz(freqband_mhz)
    if band is None:
        return NoRotor(f"<freqband> {freqband_mhz:g} MHz is no amateur band", banded)
    for r in banded:
        if band in r.bands:
            return r
    have = "; ".join(f"{r.rotator.id}: {', '.join(r.bands)}" for r in banded)
    return NoRotor(f"no rotator is for {band} ({have})", banded)


def heading(rot: Rotator, ways: Iterable[float]) -> float:
    """Rules 3 and 4: the target for a logger's heading (or either of ``ways``, N1MM's
    bidirectional), folded into 0..360, that the rotor turns least to along its travel; north
    is a direction, not an end: 0 or 360, whichever is nearer where the two are the ends of the
    travel (an attack pass: a Yaesu at 355 sent 0 turned 355 degrees back through south, and
    bidirectional took 180 for it). The first of equals; as named without a reading. The
    reading is ``pointing.raw_reading``'s (``Pointing.least_turn``): the remote's rotator reads
    the station's ``R/status``, which leaves the raw bearing out where it equals the bearing,
    and by the raw bearing alone its north went out as 0, the far end (a Yaesu at 355 turned
    back through south)."""
    return rot.pointing.least_turn(ways, rot.status)


@dataclass
class Counts:
    """What came in, per protocol (the benchmark and the tests read them)."""

    commands: int = 0
    queries: int = 0
    malformed: int = 0
    ignored: int = 0
    replies_dropped: int = 0  # over the rate limit of the address they would go to
    no_band: int = 0  # rule 5: refused, no rotator for the band


@dataclass
class Rarely:
    """What can come in floods is logged at most once per ``every_s``, with the count since."""

    every_s: float
    logged_s: float = -math.inf
    since: int = 0

    def due(self, now: float) -> int | None:
        """One more; how many to report now, or None (not yet)."""
        self.since += 1
        if now - self.logged_s < self.every_s:
            return None
        count, self.since, self.logged_s = self.since, 0, now
        return count


@dataclass(frozen=True)
class Arrival:
    """Rule 8: when the system took a datagram, on the monotonic clock, no earlier than
    ``earliest`` and no later than ``latest``."""

    earliest: float
    latest: float


class Halted:
    """Rule 8: the STOPs these ports carried out, by rotator: the rotator's ``last_halt_s``
    right after one, and when it counts from (the stop's arrival, or a STOP or lock ON from
    another interface carried out before it was read, whichever was later). One carried out
    while this one went to the judge is not lost: this one is not noted then (the rotator's
    own ``last_halt_s`` counts, the safe side)."""

    def __init__(self) -> None:
        self._after: dict[int, tuple[float, float]] = {}

    def stop(
        self,
        rot: Rotator,
        stop: Stop,
        described: str,
        arrived: Arrival | None,
        seen_s: float | None = None,
        reader: Hashable | None = None,
    ) -> None:
        """``stop`` carried out on ``rot`` (``submit``, with when it was seen: ``seen_s``,
        and the sender and port that read it: ``reader``, front.py rule 3), noted if it
        ``arrived`` stamped (its latest bound: what came before it is refused, never some of
        it carried out; and handed on as ``read_s``, rule 8)."""
        if arrived is None:  # (nothing to note: the stop first, whatever else)
            rot.submit(stop, described, seen_s=seen_s, reader=reader)
            return
        count, before = rot.halts, rot.last_halt_s
        try:
            rot.submit(stop, described, seen_s=seen_s, reader=reader, read_s=arrived.latest)
        finally:
            # noted only if it was the one halt since the look: a STOP or lock ON from another
            # interface carried out between the look and this one is when the rotator halted
            alone = rot.halts == count + 1
            if rot.last_halt_s != before and alone:
                self._after[id(rot)] = rot.last_halt_s, max(before, arrived.latest)

    def since(self, rot: Rotator) -> float:
        """When ``rot`` last halted, as rule 8 judges a datagram by."""
        last = rot.last_halt_s
        after = self._after.get(id(rot))
        return after[1] if after is not None and after[0] == last else last


class Commands:
    """Called on the loggers' thread only; ``counts`` may be read from any."""

    def __init__(self, clock: Callable[[], float], fault: Fault) -> None:
        self._clock = clock
        self._fault = fault
        self._halted = Halted()  # rule 8
        self.counts = {"pst": Counts(), "n1mm": Counts()}
        self._replies = ReplyLimiter(clock)
        self._limited_log = Rarely(JUNK_LOG_S)
        self._offset_warned: set[str] = set()
        self._no_band_log = Rarely(JUNK_LOG_S)

    # -- PstRotator -----------------------------------------------------------------------
    def pst(
        self,
        e: PstEndpoint,
        sock: socket.socket,
        port: int,
        req: PstRequest,
        peer: tuple[str, int],
        data: bytes,
        arrived: Arrival | None = None,
        seen_s: float | None = None,
    ) -> None:
        """Rules 1 to 3; ``sock`` listens on ``port`` and sends the replies; ``seen_s``: when
        it was seen where the system does not stamp datagrams (server.py rule 9); ``arrived``: when
        the system took the datagram (rule 8, monotonic), if it said."""
        counts, rot = self.counts["pst"], e.rotator
        for query in req.queries:  # rule 2, before the command: the position it had
            status = rot.status
            value = status.bearing_deg if query == "AZ" else status.elevation_deg
            counts.queries += 1
            if not status.available or value is None:
                continue
            if not self._replies.allow(peer[0]):
                self._limited(counts, peer[0])
                continue
            try:
                sock.sendto(pst_reply(query, value), (peer[0], port + 1))
            except OSError as exc:
                log.debug("PST reply to %s:%d: %s", peer[0], port + 1, exc)
        counts.ignored += len(req.ignored)
        described = "pst " + ascii_text(data).strip()  # rule 7: whole
        # who sent it (the audit trail, the lease): on the commands themselves, which every
        # rotator these endpoints serve takes (the bridge's and the remote's)
        by = Origin(Source.PST, None, peer[0])
        has_el = rot.spec.has_elevation
        el = req.elevation if has_el else None
        since = rot.halts_for(Source.PST)  # rule 8: before the look at the last halt
        seen_s = arrived.earliest if arrived is not None else seen_s  # (front.py rule 3)
        reader = ("pst", e.bind, e.port, peer)  # (front.py rule 3: the sender, on its port)
        try:
            if req.stop:
                self._halted.stop(rot, Stop(Source.PST, by), described, arrived, seen_s, reader)
            elif self._stale(rot, arrived, req.park or req.locator is not None, req.azimuth, el):
                rot.report_refusal(f"pst: {STALE}", described, origin=by)  # rule 8
                return
            elif req.park:
                park = Park(source=Source.PST, origin=by)
                rot.submit(park, described, since=since, seen_s=seen_s, reader=reader)
            elif req.locator is not None:
                try:
                    lat, lon = geo.parse_locator(req.locator)
                except geo.LocatorError as exc:
                    rot.report_refusal(f"pst: {exc}", described)  # (it names the locator)
                    return
                toward = Toward(lat, lon, req.locator, source=Source.PST, origin=by)
                rot.submit(toward, described, since=since, seen_s=seen_s, reader=reader)
            elif req.azimuth is not None and not AZ_FOLDED[0] <= req.azimuth <= AZ_FOLDED[1]:
                rot.report_refusal(
                    f"pst: azimuth {shown_past(req.azimuth, *AZ_FOLDED)} outside "
                    f"{AZ_FOLDED[0]:g}..{AZ_FOLDED[1]:g}",
                    described,
                )
                return
            elif req.azimuth is not None or el is not None:
                az = None if req.azimuth is None else heading(rot, (req.azimuth,))  # rule 3
                target = Target(az, el, Source.PST, origin=by)
                rot.submit(target, described, since=since, seen_s=seen_s, reader=reader)
            else:
                return
            counts.commands += 1
        except Refused:
            pass  # the rotator has published it on R/error

    def _stale(
        self, rot: Rotator, arrived: Arrival | None, moves: bool, *axes: float | None
    ) -> bool:
        """Rule 8: a datagram that would move ``rot`` (``moves``, or an axis given) may have
        reached the system before its last STOP or lock ON (its earliest bound)."""
        if arrived is None or not (moves or any(a is not None for a in axes)):
            return False
        return arrived.earliest < self._halted.since(rot)

    def _limited(self, counts: Counts, address: str) -> None:
        """Rule 2: a reply over the address's rate is dropped, counted, logged rarely."""
        counts.replies_dropped += 1
        count = self._limited_log.due(self._clock())
        if count is not None:
            log.info(
                "PST UDP: %d repl(ies) dropped over the rate limit, the last to %s (a client "
                "polling too fast, or queries sent in its name)",
                count,
                address,
            )

    # -- N1MM -----------------------------------------------------------------------------
    def n1mm(
        self,
        e: N1mmEndpoint,
        req: N1mmRequest,
        data: bytes,
        peer: str | None = None,
        arrived: Arrival | None = None,
        seen_s: float | None = None,
    ) -> None:
        """Rules 1 and 4 (``peer``: the sender's address; ``arrived``: rule 8; ``seen_s``: as
        ``pst``'s)."""
        by = Origin(Source.N1MM, None, peer)
        seen_s = arrived.earliest if arrived is not None else seen_s  # (front.py rule 3)
        reader = ("n1mm", e.bind, e.port, peer)  # (front.py rule 3: the sender, on its port)
        counts = self.counts["n1mm"]
        described = "n1mm " + ascii_text(data).strip()  # rule 7: whole
        if req.stop:  # a stop is never dropped: every rotor it names, every one for "*"
            names = {req.rotor, *req.also}
            stopped = [r.rotator for r in e.rotors if r.name in names or "*" in names]
            if stopped:
                self._stop_each(stopped, described, by, arrived, seen_s, reader)
                counts.commands += 1
                return
        chosen = choose(e.rotors, req.rotor, req.freqband_mhz, req.freqband_unread)  # rule 5
        if isinstance(chosen, NoRotor):
            if chosen.why is None:
                counts.ignored += 1
                log.debug("N1MM UDP %d: rotor %r is not ours", e.port, req.rotor)
            else:
                self._no_band(counts, chosen, described, by)
            return
        rot = chosen.rotator
        if e.shared(chosen.name):  # rule 6: the antenna on the radio's band
            e.current[chosen.name] = rot
        assert req.azimuth is not None
        if req.offset and req.rotor not in self._offset_warned:
            self._offset_warned.add(req.rotor)
            log.warning("N1MM rotor %r sends offset %g: not applied", req.rotor, req.offset)
        since = rot.halts_for(Source.N1MM)  # rule 8: before the look at the last halt
        if self._stale(rot, arrived, True):  # rule 8
            rot.report_refusal(f"n1mm: {STALE}", described, origin=by)
            return
        ways = (req.azimuth, req.azimuth + 180.0) if req.bidirectional else (req.azimuth,)
        az = heading(rot, ways)  # rule 4: the nearer along the travel; rule 3: north
        try:
            target = Target(az, None, Source.N1MM, origin=by)
            rot.submit(target, described, since=since, seen_s=seen_s, reader=reader)
            counts.commands += 1
        except Refused:
            pass

    def _no_band(self, counts: Counts, none: NoRotor, described: str, by: Origin) -> None:
        """Rule 5: nothing moves; said (rarely) in the log and on each candidate's R/error."""
        counts.no_band += 1
        message = f"n1mm: {none.why}: nothing turned"
        count = self._no_band_log.due(self._clock())
        if count is not None:
            log.warning("%s (%d such since the last line)", message, count)
        for r in none.could:
            try:
                r.rotator.report_refusal(message, described, origin=by)
            except Exception as exc:
                self._fault(f"reporting an N1MM refusal on rotator {r.rotator.id!r}", exc)

    def _stop_each(
        self,
        rotators: Iterable[Rotator],
        described: str,
        by: Origin | None = None,
        arrived: Arrival | None = None,
        seen_s: float | None = None,
        reader: Hashable | None = None,
    ) -> None:
        """Rule 4: a fault behind one rotator's stop does not keep it from the next."""
        stop = Stop(Source.N1MM, by)
        for rot in rotators:
            try:
                self._halted.stop(rot, stop, described, arrived, seen_s, reader)  # rule 8
            except Refused:  # the remote's, sent but maybe to nobody: reported there (no fault)
                pass
            except Exception as exc:
                self._fault(f"the N1MM stop of rotator {rot.id!r}", exc)
