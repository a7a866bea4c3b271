"""The station's heartbeat and the send time it lends the remote's commands: both sides, pure
(no paho, no thread of its own; the clocks are handed in).

A command from ``rotor-bridge remote`` may be held up on its way (a link that stalls for seconds
without dropping, then delivers what it held); the MQTT message expiry starts only at the broker,
so only a time stamped at the sender can tell the station how old a command is. The two
computers' clocks need not agree, so the remote does not stamp its own clock: it stamps the
station's clock as the station's heartbeat lets it reckon it, never later than the truth.

Rules:
1. The station's bridge publishes its clock (unix seconds: rule 6) on ``B/bridge/heartbeat`` every
   HEARTBEAT_S while its main connection is up (after its first look; not when it refused to
   run), QoS 0, NOT retained: one that arrives is a bridge alive now (a retained value the
   broker restored from its file is no news of anyone).
2. The remote counts the station as heard only while a heartbeat came as published within
   SILENT_S on its own monotonic clock (remote/rotator.py); until then every move is refused.
3. The remote reckons the station's clock (``StationClock``): each heartbeat says the station's
   time ``t`` when it left, so at its arrival the station's clock is at least ``t``; the remote's
   monotonic clock plus the largest such offset over the last CLOCK_WINDOW_S is never later than
   the station's clock (up to the drift of two clocks over the window, milliseconds). The
   error is the fastest trip down the link: a command's age reads longer than it was, the safe
   direction. A station clock stepped back reads as a stamp from the future (rule 5), refused
   until the window has forgotten the old beats; one stepped forward is learnt from the next
   beat. No heartbeat within the window: no reckoning, and the remote stamps nothing. The beats
   are kept one per second of arrival (the largest offset of that second), so a flood on the
   heartbeat topic costs no command more than a minute's worth of beats.
4. A command carries its send time on the station's clock and its expiry as the MQTT 5 user
   properties ``sent`` and ``expiry`` (``Stamp``; and ``station``: rule 7); a stop and a lock
   ON may go unstamped.
5. The station refuses a command whose stamp says it is older than its expiry, or from more
   than AHEAD_S in the future (the reckoning went wrong: refused, and said), or a stamp it
   cannot read: an ``expiry`` without ``sent`` too (an attack pass: a Node-RED flow that set
   only ``expiry`` had its commands carried out however late, and not a word), such as a
   property given twice with two values or digits other than ASCII's (an attack pass: of two
   ``sent`` the last was taken, and ``１２３`` was read as 123), or with a stamp's name in other
   letters (``SENT``, ``Expiry``: MQTT's names are case-sensitive, and a flow that meant a
   stamp had its commands carried out however late). A ``sent`` in
   milliseconds (JavaScript's ``Date.now()``) is said to be one, not a clock that went back.
   Stop and lock ON are never refused (docs/architecture.md rule 11): the service does not
   ask. A command without a stamp (a dashboard, Home Assistant) is judged as before: it has
   only the broker's expiry.
6. The station's clock, the one its heartbeats carry and the one it judges a stamp by, is its
   wall clock never set back (``StationTime``; docs/architecture.md rule 15): its steady clock
   plus the largest offset between the two this process has seen. A wall clock set back (a
   time server found after boot) would otherwise make a command the link held up look younger
   by the step (one held for its expiry plus the step would turn the rotor), and a fresh one
   reckoned from a beat before the step look as if from the future. Set back, the station's
   clock goes on from where it was, ahead of the wall clock by the step, until the process
   ends; set forward, it follows at once (a command stamped before the step looks older by
   it, the safe direction). A client that stamps by its own synchronised wall clock instead
   of the heartbeat's (rule 4 allows it) sees its commands look older by a step back.
7. Rule 6 holds within one process only: a station's bridge that restarts after its wall clock
   was set back starts from the lower wall clock, while the remote still reckons from the old
   process's beats (rule 3, up to CLOCK_WINDOW_S): a command the link held up would look
   younger by the step, and fresh ones ahead. So each beat names the station process it comes
   from, as the MQTT 5 user property ``station`` (``StationTime.identity``, a random token made
   at start; the payload is unchanged), and the remote forgets its reckoning whenever a beat
   names another process than the beat before it (``StationClock.heard``; a beat without one,
   an older station's or one that speaks MQTT 3.1.1, is a process of no name). A command
   stamped from a reckoning carries that process's name beside ``sent`` (``Stamp.station``;
   from beats of no name it carries NAMELESS, the empty name: a station that names itself
   is not that process, so the bridge restarted since, upgraded or under MQTT 5), and the
   station refuses a stamp naming another process than itself (stamped against the
   station's bridge before it restarted); a stamp without the property (an older remote,
   another client that stamps) is judged as rule 5 says. An older station ignores the
   property, an older remote never sends it, a station under MQTT 3.1.1 reads no stamp.
8. A move stamped before the rotator's last STOP or lock ON is refused, however fresh
   (service.py rule 9; an attack pass: a remote's target held up by its link for 3 s, a STOP
   from Home Assistant meanwhile, and the target turned the rotor when it came). A halt's
   time is when it came, or the stamp it carries if that is earlier and would pass as a
   move's (rule 5: within its expiry; ``Stop.sent_s``; a clock minutes slow must not open a
   window for the moves stamped between its stamp and its arrival, a review): so
   the remote stamps its halts too, when it has a reckoning (a halt never waits for one),
   and a move its operator sends right after a STOP is not taken for older than the STOP
   however long the link's trip. A client that stamps its moves by its own clock should
   stamp its stops too.
9. A message's MQTT 5 properties are read only up to MAX_PROPERTIES_BYTES (a stamp and an
   operator's name take some hundred bytes): paho reads user properties in time that grows
   with the square of their number, and one PUBLISH of 120,000 short ones (3.7 MB, under the
   4 MiB the bridge takes: connection.py rule 18) held the main connection's thread for four
   minutes, until the broker gave the connection up and sent the message again (an attack
   pass). A longer section is not read (paho_client.py rule 10): the message comes with the
   user property UNREAD_PROPERTIES alone, naming the section's size, and a stamp that says
   so (``Stamp.unread``): a move so sent is refused, saying why; a stop and a lock ON are
   carried out as any unreadable stamp's (rule 5).
10. A command may be stamped with when its bytes were seen at the remote, not when it is sent
   (``StationClock.stamp``'s ``seen_s``, on the remote's monotonic clock: front.py rule 3):
   the station's clock then, reckoned now (rule 3: never later than the truth), floored to its
   millisecond (never rounded up past the truth). A STOP the station took another way (Home
   Assistant, its console) after the bytes came refuses it there (rule 8), however late the
   remote read it (a review: a rotctld ``P`` sent before a STOP from Home Assistant, its
   client paused over its budget, was read after it, stamped when sent and turned the rotor).
   A halt is stamped with when it was seen too, so a move is never lifted past its own halt's
   seen time; a move is never stamped before ``after``, the stamp of the last halt the remote
   sent for its rotator that the move's own reader read (remote.py rule 8; the client's own
   ``S`` then ``P``, read in one go: the ``P`` is stamped as the ``S``, and the station,
   comparing the two stamps directly, takes it for not older: service.py rule 9), never
   another front end's (an attack pass: lifted to PstRotator's STOP, Gpredict's ``P`` seen
   before it turned the rotor). The reckoning rule 8 keeps from going back is the send time's.
11. A message without a stamp carries no send time, but the station can tell that its broker
   held messages up (frozen, not gone: an SD card writing the broker's file, a VM paused, a
   swap storm; attack 13: a target held 10 s turned the rotor when the broker ran on): the main
   connection reads its own beats back (``Echo``, client.py rule 19), each known by its exact
   payload (this process's clock to the millisecond as it went, under MQTT 3.1.1 too: another
   bridge's beat is no echo of ours; a forger who copies ours at once can only make the broker
   look quick, as it looked before this rule), and its network thread says what it saw
   (paho_client.py rule 11): a poll that found nothing to read proves that nothing came from
   the last read up to it, whatever the thread's scheduling. The broker HELD the bridge up when
   bytes are read after such quiet through which a beat of ours was out for QUIET_S or more:
   the broker had the beat and passed nothing on. A late beat alone proves nothing: a main
   connection kept seconds behind by a backlog (a burst of 10,000 targets, a flood on any topic
   it reads) reads its own beats seconds late, as from a stalled broker, but never sees quiet
   (its socket always has bytes), and the reverted first design refused the burst's newest
   target after older ones were carried out (the newest word must win). From a hold on, until
   a beat sent after it comes back (what the broker held is ahead of that beat: mosquitto reads
   every ready socket in each round of its loop; one goes at once, not a beat period later), a
   move read on the main connection is refused, a stamped one too (service.py rule 12; review
   61: a stamped move let through stood over a newer unstamped one refused); the hold is
   judged before anything in the read that ended the quiet is handled, so held beats read
   before the held target, or after it, change nothing. A beat goes out every HEARTBEAT_S, up
   to a second later (paho's loop, paho_client.py rule 2), and the thread sees quiet to within
   a second: a move held up QUIET_S + HEARTBEAT_S + 2 s (7 s) or more is always refused, one
   held QUIET_S or more may be (the console and the remote refuse one at 5 s). A healthy link sees a
   beat out for a round trip; one whose echoes come in a pipeline (a round trip longer than
   the beat period) reads an echo every beat period: neither sees QUIET_S with a beat out, nor
   does an idle bridge with its heartbeat off (no beat out). A link whose round trip is QUIET_S
   or more holds every message that long, and a move over it may be refused, the safe side.
   No clock decides anything but a refusal (docs/architecture.md rule 15): a broker that is
   quick again lets the next move through, and one none of whose beats were read back on this
   connection (an ACL that denies reading the heartbeat topic: mosquitto grants the
   subscription and drops the messages) is never called late. That is said once (client.py
   rule 19) after UNREAD_S of quiet seen with a beat out, never for a backlog however long (a
   start-up reading tens of thousands of retained topics sees no quiet: its beats are behind
   them, not unread). A new connection starts clean. The beats out are kept by payload,
   MAX_ECHOES at most (the oldest go first: a broker frozen longer than that still shows a
   beat out through the quiet).
"""

from __future__ import annotations

import math
import secrets
import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

HEARTBEAT_S = 2.0  # rule 1
SILENT_S = 3 * HEARTBEAT_S  # rule 2: three beats missed
CLOCK_WINDOW_S = 60.0  # rule 3
BUCKET_S = 1.0  # rule 3: beats kept one per second of arrival
MAX_BUCKETS = int(CLOCK_WINDOW_S / BUCKET_S) + 2
AHEAD_S = 1.0  # rule 5
SENT, EXPIRY = "sent", "expiry"  # rule 4: the user properties
STATION = "station"  # rule 7: the user property naming the station's process
NAMELESS = ""  # rule 7: the name a stamp gives a process whose beats named none
MAX_EXPIRY_S = 3600.0
MAX_PROPERTIES_BYTES = 4096  # rule 9: a PUBLISH's properties read, at most
UNREAD_PROPERTIES = "rotor-bridge unread properties"  # rule 9: in their place, their size
# rule 11: quiet seen this long with a beat out, the broker held the bridge up (a healthy link
# sees a beat out a round trip, a pipelined one under a beat period: HEARTBEAT_S and up to 1 s);
# plus a beat period and paho's seconds, 7 s (the console and the remote refuse a move at 5 s)
QUIET_S = 3.0
MAX_ECHOES = 32  # rule 11: the beats out kept (a minute of them)
UNREAD_S = 5 * HEARTBEAT_S  # rule 11: none back through this much quiet with one out: unread


def beat_payload(now_unix: float) -> str:
    """Rule 1: the station's wall clock, unix seconds to the millisecond."""
    return f"{now_unix:.3f}"


def beat_properties(identity: str) -> list[tuple[str, str]]:
    """Rule 7: the user properties of a heartbeat, naming the station's process."""
    return [(STATION, identity)]


def station_of(pairs: list[tuple[str, str]]) -> str | None:
    """Rule 7: the station process a heartbeat's or a stamp's user properties name; None
    without one, or with two that differ (read as neither, as a stamp's: rule 5)."""
    named = {str(value) for key, value in pairs if key == STATION}
    return named.pop() if len(named) == 1 else None


def parse_beat(payload: bytes) -> float:
    """A heartbeat's time; ValueError for anything but a finite positive number."""
    t = float(payload.decode("ascii", "replace"))
    if not math.isfinite(t) or t <= 0:
        raise ValueError(f"{payload[:20]!r} is no time")
    return t


class Beat:
    """Rule 1 on the station: whether a heartbeat is due (``due`` is asked often)."""

    def __init__(self, every_s: float = HEARTBEAT_S) -> None:
        self._every_s = every_s
        self._last = -math.inf

    def due(self, now: float) -> bool:
        if now - self._last < self._every_s:
            return False
        self._last = now
        return True


class Echo:
    """Rule 11 on the station: the bridge's own beats read back, the quiet the network thread
    saw, and whether the broker held the bridge up. Pure (the monotonic time handed in); the
    caller keeps it under one lock (client.py rule 19)."""

    def __init__(self, quiet_s: float = QUIET_S, unread_s: float = UNREAD_S) -> None:
        self._quiet_s = quiet_s
        self._unread_s = unread_s
        self._out: dict[bytes, float] = {}  # payload -> sent, oldest first
        self._read = False  # one of this connection's beats came back
        self._heard = -math.inf  # the last read that found bytes ended then
        self._quiet_to: float | None = None  # an empty poll proved nothing came from then to this
        self._unread_quiet_s = 0.0  # quiet seen with a beat out while none came back, summed
        self._held_at: float | None = None  # held up: judged then; late until a beat sent
        self._held_s = 0.0  # ... after it is back; the longest quiet meanwhile

    def connected(self) -> None:
        """A new connection: nothing of the last one comes back on it, nothing was heard yet."""
        self._out.clear()
        self._read, self._heard, self._quiet_to = False, -math.inf, None
        self._unread_quiet_s, self._held_at, self._held_s = 0.0, None, 0.0

    def sent(self, payload: bytes, now: float) -> None:
        self._out[payload] = now
        while len(self._out) > MAX_ECHOES:
            del self._out[next(iter(self._out))]

    def quiet(self, until: float) -> None:
        """An empty poll: nothing came on the connection from the last read up to ``until``."""
        if until > self._heard and (self._quiet_to is None or until > self._quiet_to):
            self._quiet_to = until

    def reading(self, now: float) -> None:
        """Bytes wait and are about to be read (the messages in them handled inside the read):
        the quiet seen since the last read is over; judged before any of them is handled."""
        quiet_to, self._quiet_to = self._quiet_to, None
        if quiet_to is None:
            return  # (a backlog: every poll found bytes)
        waited_s = self._waited(quiet_to)
        if not self._read:
            self._unread_quiet_s += waited_s
        if waited_s >= self._quiet_s:  # the broker held a beat of ours that long, silent
            self._held_at = now
            self._held_s = max(self._held_s, self._quiet_for(quiet_to))

    def read(self, now: float) -> None:
        """The read is over: quiet, if any, is counted from now."""
        self._heard = now

    def back(self, payload: bytes, now: float) -> bool:
        """A beat read back: True if it was one of ours out."""
        sent = self._out.pop(payload, None)
        if sent is None:
            return False
        for older in [p for p, t in self._out.items() if t <= sent]:
            del self._out[older]  # (the broker keeps one order: those are lost, not late)
        self._read = True
        if self._held_at is not None and sent >= self._held_at:
            self._held_at, self._held_s = None, 0.0  # sent after the hold ended: caught up
        return True

    def late(self, now: float) -> float | None:
        """How long the broker held the bridge up (the quiet seen), while it is late now: a hold
        judged and no beat sent after it back yet, or a beat out through QUIET_S of quiet seen
        so far; None when it is not, or when no beat of this connection has come back (nothing
        to judge by: an ACL that denies reading them)."""
        if not self._read:
            return None
        if self._held_at is not None:
            return self._held_s
        quiet_to = self._quiet_to
        if quiet_to is not None and self._waited(quiet_to) >= self._quiet_s:
            return self._quiet_for(quiet_to)
        return None

    @property
    def returning(self) -> bool:
        """A hold was judged and no beat sent after it yet: one should go at once."""
        held_at = self._held_at
        return held_at is not None and all(t < held_at for t in self._out.values())

    def unread(self, now: float) -> bool:
        """No beat of this connection came back though one was out through UNREAD_S of quiet
        seen (a backlog, however long, shows no quiet: its beats are behind it, not unread)."""
        if self._read:
            return False
        quiet_to = self._quiet_to
        open_s = 0.0 if quiet_to is None else self._waited(quiet_to)
        return self._unread_quiet_s + open_s > self._unread_s

    def _quiet_for(self, quiet_to: float) -> float:
        """How long nothing came, up to ``quiet_to`` (what is said: the hold's length)."""
        return quiet_to - self._heard if self._heard > -math.inf else self._waited(quiet_to)

    def _waited(self, quiet_to: float) -> float:
        """The part of the quiet up to ``quiet_to`` through which a beat of ours was out."""
        oldest = next(iter(self._out.values()), None)
        if oldest is None:
            return 0.0
        return max(0.0, quiet_to - max(self._heard, oldest))


class StationClock:
    """Rule 3 on the remote: the station's clock reckoned from its heartbeats; ``clock`` is the
    remote's monotonic clock. ``heard`` runs on paho's thread and ``now_unix`` on the senders',
    so both hold a lock; beats are kept one per BUCKET_S of arrival (the largest offset), at
    most MAX_BUCKETS, so anyone beating fast costs nothing more than one beat a second."""

    def __init__(self, clock: Callable[[], float]) -> None:
        self._clock = clock
        self._lock = threading.Lock()
        # (first arrival, the largest station - arrival among the beats from then on)
        self._offsets: deque[tuple[float, float]] = deque(maxlen=MAX_BUCKETS)
        self._station: str | None = None  # rule 7: the process the offsets came from
        # rule 8: the last reckoning given (the station's time, its process): the next is never
        # earlier by up to AHEAD_S (the best beat leaving the window drops the reckoning by the
        # trips' spread, and a move sent after this remote's STOP was stamped before it)
        self._given: tuple[float, str | None] | None = None

    def heard(self, station_unix: float, station: str | None = None) -> None:
        """A live beat; ``station``: the process it names (rule 7), None for none."""
        with self._lock:
            now = self._clock()
            if station != self._station:  # rule 7: another process, another clock
                self._offsets.clear()
                self._station = station
            offset = station_unix - now
            if self._offsets and now - self._offsets[-1][0] < BUCKET_S:
                first, best = self._offsets[-1]
                self._offsets[-1] = (first, max(best, offset))
            else:
                self._offsets.append((now, offset))
            self._trim(now)

    def forget(self) -> None:
        """The connection dropped: what comes next is learnt anew."""
        with self._lock:
            self._offsets.clear()

    def now_unix(self) -> float | None:
        """The station's clock now, never later than it (rule 3); None without a recent beat."""
        reckoned = self.reckon()
        return None if reckoned is None else reckoned[0]

    def reckon(self, seen_s: float | None = None) -> tuple[float, str | None] | None:
        """``now_unix`` and the station process its beats came from (rule 7), read together;
        ``seen_s`` (rule 10): the station's clock then instead, reckoned now (the next
        reckoning is never earlier than this one's now, rule 8, whatever ``seen_s``)."""
        with self._lock:
            now = self._clock()
            self._trim(now)
            if not self._offsets:
                return None
            reckoned = now + max(offset for _, offset in self._offsets)
            given = self._given
            if given is not None and given[1] == self._station:
                if reckoned < given[0] <= reckoned + AHEAD_S:
                    reckoned = given[0]
            self._given = reckoned, self._station
            if seen_s is not None and seen_s < now:  # rule 10: backdated
                reckoned -= now - seen_s
            return reckoned, self._station

    def stamp(
        self,
        expiry_s: float,
        seen_s: float | None = None,
        after: tuple[float, str] | None = None,
    ) -> Stamp | None:
        """Rules 4 and 7: a command's stamp sent now, naming the process the reckoning came
        from (NAMELESS for beats that named none); None without a recent beat. Rule 10:
        ``seen_s``, when the command was seen (this clock's), stamped then instead, but never
        before ``after``, a halt's stamp (its time, the process it names); every stamp is its
        millisecond's start."""
        reckoned = self.reckon(seen_s)
        if reckoned is None:
            return None
        sent, station = reckoned
        sent = math.floor(sent * 1000.0) / 1000.0  # (the stamp's millisecond: never later)
        name = NAMELESS if station is None else station
        if after is not None and after[1] == name and after[0] > sent:
            sent = after[0]
        return Stamp.of(sent, expiry_s, name)

    def _trim(self, now: float) -> None:
        while self._offsets and now - self._offsets[0][0] > CLOCK_WINDOW_S:
            self._offsets.popleft()


def _span(seconds: float) -> str:
    """An age in an error's words: tenths of a second, or three digits and the power of ten
    where there are more (an attack pass: ``sent=-1e308`` was told in a 300-digit number)."""
    return f"{seconds:.1f} s" if abs(seconds) < 1e6 else f"{seconds:.3g} s"


def _seconds(text: str | None) -> float:
    """A stamp's number (rule 5), NaN for none or one that cannot be read: ASCII digits only
    (``float`` reads ``１２３``)."""
    if text is None or not text.isascii():
        return math.nan
    try:
        return float(text)
    except ValueError:
        return math.nan


class StationTime:
    """Rule 6 on the station: ``now_unix`` is the station's clock (its heartbeats carry it, its
    stamps are judged by it); ``wall`` and ``clock`` (the steady one) are read under a lock,
    from paho's thread (the beat) and whichever thread judges a command. ``identity`` names
    this process's clock (rule 7): a random token unless one is given."""

    def __init__(
        self, wall: Callable[[], float], clock: Callable[[], float], identity: str | None = None
    ) -> None:
        self.identity = secrets.token_hex(8) if identity is None else identity
        self._wall = wall
        self._clock = clock
        self._lock = threading.Lock()
        self._offset = -math.inf  # the largest wall - steady seen

    def now_unix(self) -> float:
        with self._lock:
            now = self._clock()
            offset = self._wall() - now
            if offset > self._offset:
                self._offset = offset
            return now + self._offset


@dataclass(frozen=True)
class Stamp:
    """Rule 4: a command's ``sent`` and ``expiry`` user properties, as they came; rule 7: the
    station process ``sent`` was reckoned from (``station``: NAMELESS for a process whose beats
    named none), None without the property."""

    sent: str
    expiry: str | None
    station: str | None = None
    miscased: str | None = None  # rule 5: a stamp's name in other letters (``SENT``), as it came
    unread: str | None = None  # rule 9: the size of the properties not read, as paho_client said

    @classmethod
    def of(cls, sent_unix: float, expiry_s: float, station: str | None = None) -> Stamp:
        return cls(f"{sent_unix:.3f}", f"{expiry_s:g}", station)

    def properties(self) -> list[tuple[str, str]]:
        named = [] if self.station is None else [(STATION, self.station)]
        return [(SENT, self.sent), (EXPIRY, self.expiry or ""), *named]

    @classmethod
    def of_properties(cls, pairs: list[tuple[str, str]]) -> Stamp | None:
        """The stamp among a message's user properties; None without ``sent`` and ``expiry``
        (an ``expiry`` alone is a stamp whose send time cannot be read: rule 5) and with its
        properties read (rule 9)."""
        found: dict[str, str] = {}
        miscased = unread = None
        for key, value in pairs:
            key, value = str(key), str(value)
            if key in (SENT, EXPIRY, STATION):  # one given twice, two ways: read as neither
                found[key] = value if found.get(key, value) == value else "\0twice"
            elif key.casefold() in (SENT, EXPIRY) and miscased is None:  # rule 5
                miscased = key
            elif key == UNREAD_PROPERTIES:  # rule 9
                unread = value
        if SENT not in found and EXPIRY not in found and miscased is None and unread is None:
            return None
        return cls(found.get(SENT, ""), found.get(EXPIRY), found.get(STATION), miscased, unread)

    def sent_unix(self, station: str | None = None) -> float | None:
        """Rule 8: the send time, if it can be read and was reckoned against this station
        process (``station``, as ``judge`` asks); None otherwise."""
        sent = _seconds(self.sent)
        return None if self._another(station) or not math.isfinite(sent) else sent

    def expires_unix(self, station: str | None = None) -> float | None:
        """When the command expires (its send time and expiry, as ``sent_unix`` reads the
        first), or None where either cannot be read."""
        sent = self.sent_unix(station)
        ends = math.nan if sent is None else sent + _seconds(self.expiry)
        return ends if math.isfinite(ends) else None

    def _another(self, station: str | None) -> bool:
        """Rule 7: reckoned against another station process than ``station``."""
        return self.station is not None and station is not None and self.station != station

    def judge(self, now_unix: float, station: str | None = None) -> str | None:
        """Rules 5 and 7: why the command is refused, or None (fresh); ``station``: the
        judging process's identity (None: no stamp's name is asked)."""
        if self.unread is not None:
            return (
                f"its MQTT 5 properties take {self.unread[:12]} bytes, more than the "
                f"{MAX_PROPERTIES_BYTES} the bridge reads (a stamp and an operator's name take "
                "some hundred): not carried out"
            )
        if self._another(station):
            return (
                "stamped against this station's bridge before it restarted: not carried out; "
                "send it again"
            )
        if self.miscased is not None:
            return (
                f"its user property {self.miscased[:24]!r} is no stamp: the names are "
                f"{SENT!r} and {EXPIRY!r}, in small letters (MQTT's names are case-sensitive): "
                "not carried out"
            )
        sent = _seconds(self.sent)
        expiry = _seconds(self.expiry) if math.isfinite(sent) else math.nan
        if not (math.isfinite(sent) and math.isfinite(expiry) and 0 < expiry <= MAX_EXPIRY_S):
            return (
                f"its send time cannot be read (user properties {SENT}={self.sent[:24]!r}, "
                f"{EXPIRY}={(self.expiry or '')[:24]!r}): not carried out"
            )
        age = now_unix - sent
        if age > expiry:
            return (
                f"sent {_span(age)} ago, older than its {expiry:g} s expiry (a link that held it "
                "up): not carried out"
            )
        if age < -AHEAD_S and sent > now_unix * 100:  # (JavaScript's Date.now(): a Node-RED flow)
            return (
                f"its send time {SENT}={self.sent[:24]!r} is in milliseconds: give unix seconds "
                "on the station's clock: not carried out"
            )
        if age < -AHEAD_S:
            return (
                f"stamped {_span(-age)} ahead of this station's clock (the station's clock went "
                "back?): not carried out; send it again in a minute"
            )
        return None
