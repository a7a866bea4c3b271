"""The remote's one connection to the station's broker (``rotor-bridge remote``): it reads the
station's retained state and publishes commands that are never late.

It is the bridge's Connection (connection.py: protocol, TLS, credentials, reconnects, one log
line per reason) with other topics and one more duty: sending a command.

Rules:
1. MQTT 5 only (the remote's settings refuse 3.1.1): a command must carry an expiry.
2. A command is published at QoS 1, never retained, with a message expiry interval of a few
   seconds (a command stuck in a broker queue dies there) and the operator as the user
   property ``operator``.
3. Never late: while the connection is not up, ``send`` raises Refused(OFFLINE) at once and
   nothing is queued (a halt excepted: rule 6). paho keeps an unacknowledged QoS 1 message
   and sends it again on the next connection (its ``_messages_reconnect_reset_out``), which
   would move the antenna minutes after the operator asked; so when the connection drops,
   every command not yet acknowledged is dropped from paho's queue, under the same lock
   ``send`` holds (but see rule 6). The remote publishes nothing else at QoS 1, so the whole
   queue is commands.
4. The state topics are subscribed at QoS 0: the newest retained value is what counts, and it
   comes again after every reconnect. Unlike the bridge's command topics they do not ask for
   retain-as-published, so the retain flag the handler gets says "replayed from the broker's
   store on subscribing" (an old value, of unknown age) and a message the station publishes
   while we listen comes without it (remote/rotator.py rule 1 times a moving status by that).
5. Until the first connection is accepted, a refusal or a failed attempt is not logged (the
   start-up error says it, once, in one line: ``failure``, also when the broker closed the
   connection without a word, or never answered it: connection.py rule 6); a refused login,
   a broker without MQTT 5 or a TLS handshake that fails is ``fatal``, for the start to end
   at once, since trying again cannot mend it.
   Once the remote has been connected, both are logged and retried as the bridge does
   (connection.py rule 6).
6. A stop is never lost (docs/architecture.md rule 11; a stop moves nothing, rule 7): an
   unacknowledged command that ``last_word`` says is one (a stop, lock ON) and that its
   client was told went out is kept when the rest are dropped, and sent again, with a fresh
   expiry, first thing on the next connection, before any other command can be sent. So is
   one sent while the connection is down or being reset (rule 7): ``send`` keeps it (once,
   however often it is pressed) and raises Refused(OFFLINE, KEPT), the truth for its client:
   not delivered yet (rotctld ``RPRT -6``), kept and sent first on reconnect. Any other
   command is refused then, and never sent later (rule 3). What was kept is sent once more at
   the first live heartbeat of the new connection (the station's bridge heard there, so
   subscribed), and kept again if that connection drops first: the broker may come back
   before the station's bridge does (its back-off, its own restart), and the stop sent first
   then went to nobody (an attack pass: the rotor turned on to its last target). Nothing else
   can go in between: every other command needs a heartbeat heard on the connection (rule 8).
   So is a halt sent while the station's bridge is not heard (``until_heard``: its bridge
   restarting, its own link down; remote/rotator.py rule 3), at the first live heartbeat
   after it: a bridge that starts again, or connects again, with a clean session never got it.
   Nothing asked after a halt kept so goes before it: a later command (a move the station's
   bridge, back on its broker, takes before its first heartbeat came) sends the halts kept
   first, and on the halt's own topic (a lock OFF after a lock ON) is the last word: that
   halt is not sent again after it. A later move ends their wait (sent again after it, a
   STOP would stop it); a later command that never moves (tracking off, a lock OFF: they go
   whenever the link is up, and so to nobody too) does not: they still go again at the
   heartbeat (a review: a tracking OFF after a STOP to a restarting bridge spent the STOP's
   second sending, and the rotor turned on to its last target).
7. ``send`` returns only once the broker acknowledged the command (PUBACK) within
   ACK_WAIT_S; otherwise the link stalls: the connection is reset (what it holds unsent is
   dropped, rule 3) and the command refused. A caller that must not wait so does not call
   it on its own thread: the remote's PstRotator ports hand their moves to a sender of their
   own (remote/courier.py; attack 29: the loggers' one thread, waiting a round trip per
   target, held a STOP behind a burst of 190 for up to 10 s).
8. A command is stamped with its send time on the station's clock as its live heartbeats let
   the remote reckon it (heartbeat.py), and with the station process that reckoning came
   from (the heartbeats' user property ``station``, empty if they named none: heartbeat.py
   rule 7); without one heard, a move is refused. A halt is stamped too when there is a
   reckoning (the station takes a move stamped before a halt for stale: heartbeat.py rule 8,
   and a move sent right after this remote's own STOP must not be), and goes unstamped when
   there is none: nothing about the heartbeat can keep it back. A command sent with
   ``seen_s`` (when it was seen at the remote: remote/rotator.py rule 7) is stamped then
   instead (heartbeat.py rule 10), a halt too; a move never before the latest stamp a halt
   on one of its ``after`` topics (its rotator's stop and lock) went out with from the move's
   own source (``reader``: its connection or port, which orders its own bytes: ``P 300``,
   ``S``, ``P 200`` read in one go ends at 200; none said, none: a command stamped when it
   is sent, the console's, needs none, that stamp never goes back): so a move is lifted at
   most to its own source's last halt's seen time, never to that halt's send time (a review:
   ``S`` then ``P`` read late behind a STOP from Home Assistant, the ``P`` lifted to the
   ``S``'s send time, turned the rotor), and never to another source's halt (an attack pass:
   Gpredict's ``P`` seen at 8 s, read after PstRotator's STOP seen at 9 s, was lifted to 9 s
   and turned the rotor after it). A kept halt sent again (rule 6) is stamped with when it
   was last asked (``_halt_seen``: its seen time, or its send time for one sent without;
   the same halt pressed again while kept counts from the last press), by the reckoning of
   the moment it goes again (at a beat, that beat's, heard first under the send lock), and
   its stamp's ``expiry`` lengthened by the time it was kept, for the station to take it as
   sent then (service.py's HALT_STAMP_MAX_S); so a move seen before it stays before it and
   one seen after it, read before or after it goes again, does not (review 28: stamped when
   sent again and lifting every source's moves to that, it lifted Gpredict's ``P`` seen
   before PstRotator's STOP past that STOP and a Home Assistant STOP; and a move sent right
   after the kept halts went ahead of it was stamped before them). Kept over
   AGAIN_SEEN_MAX_S (the station would count its stamp from when it came) it is stamped
   when sent again, and a move seen before that is refused, the safe side; with no
   reckoning yet (on reconnect, before a beat), it goes as it was. It is noted for its own
   source as when first sent, unless stamped when sent again: then nothing is noted, and
   that source's moves keep their own seen time, one seen before the resend refused, the
   safe side (review 30: noted, the resend's stamp lifted that source's ``P`` seen before
   a Home Assistant STOP, read after the resend, to its send time). And the remote compares
   seen times on its own clock first: a move sent with ``seen_s`` before the latest seen
   time of a halt on one of its ``after`` topics that it sent or kept (``_halt_latest``,
   any source's, the console's too) is refused here (STALE, SEEN_BEFORE_HALT), whatever
   the stamps say: a stamp rests on the reckoning of the moment it is made, after a fresh
   connection one beat's, short by its trip, so a halt stamped then can land after a move
   another source saw before it, stamped after a beat with a shorter trip (review 30:
   Gpredict's ``P`` seen at 8.9 s, read late, went out stamped after PstRotator's STOP seen
   at 9 s). Equal seen times are not refused (one read: ``P 300``, ``S``, ``P 200`` ends at
   200); a move without ``seen_s`` (the console's, stamped when sent) is not checked. But a
   seen time is its reader's lower bound (the last look that found nothing waiting), and two
   readers' lower bounds do not order what they read: PstRotator's turn came before a
   rotctld ``S``, the loggers' last look at its port (no datagram stamps) was after the
   rotctld connection's, the turn was dated after the ``S``, let through and stamped after
   the STOP, and the rotor turned after it (review 33's case across interfaces). So each
   halt is noted with its read time too (``read_s``: the latest it can have come, a kernel's
   datagram stamp where the reader has one, else when it is sent here; ``_halt_read``: by
   topic, the two sources with the latest reads, so every source's latest halt but its own
   is there), and a move is refused if seen before the read time of a halt from another
   source than its own (none said: any halt's) (STALE, MAYBE_BEFORE_HALT): it goes after
   such a halt only if its earliest arrival is after the halt's latest. Against its own
   source's halts (one connection, one port and sender, read in the order they came) seen
   times alone order them, as above. The cost: a move another program sent right after a
   STOP, seen before that STOP was read, is refused too (send it again: Gpredict's next
   ``P`` goes); with the kernel's stamps the window is the stamp's microseconds. The floor
   above stays for the station's judging. Every stamp is its millisecond's start. The
   sources noted are the last HALT_READERS (a program opening a connection per STOP would
   else grow them without end, each keeping its connection); a source forgotten lifts
   nothing, so its next move may at worst be refused, never let through.
9. One command is handed to paho at a time (the send lock), in the order the broker then takes
   them: a move that may not go after a stop another thread sent meanwhile (remote/rotator.py
   ``submit``) is asked so under that lock, right before it is handed on, so a stop that
   counted itself before that is never overtaken, and one that counts itself after it goes
   after it.
10. The broker's PUBACK says the broker has a halt, not that the station's bridge does: a
   station whose route to the broker dies without a word (no FIN: its last will only after 1.5
   keepalives) is still heard for up to SILENT_S, and the broker hands the halt to its dead
   connection; the bridge comes back with a clean session and never gets it (attack 26: the
   STOP answered ``RPRT 0``, the rotor turned on to its target). So every halt the broker took
   (``send``'s, and each sent again: rule 6) is held (``_unproven``), and ORDER decides what
   becomes of it, never a clock (review 79: the station's wall clock set back, no status was
   ever after a halt) nor a guess. The station's ``R/status`` says where it stands in the
   order of its rotator's commands (``order``: session/mailbox.py rule 10a's places, which go
   on across restarts, runtime/kept.py rule 12; the run of its bridge, ``run``, and the place
   that run counts on after, ``since``; the newest it shows every command up to, ``taken``;
   the place of the command the turn shown comes from, ``turn``, or of the bridge's own turn,
   an auto-park or a storm's park, which takes a place when it begins (review 83: with none,
   an old STOP went again over an auto-park begun after it and stopped it short of the park);
   of the last lock word, ``lock``: core/model.py ``Order``). A halt is stamped from the
   places (``taken``) its rotator's statuses (replayed or not) showed, by run, before it was
   asked: judged by a status of a run showing every command up to ``taken``, its stamp is the
   newest place seen before it that this status confirms (``held_stamp``): one of that run not
   past ``taken`` (the station's own ``taken`` never goes back within a run, so a place seen
   past it was not the station's: review 83, a status forged far ahead stamped a STOP so that
   it went again over Home Assistant's newer turn), or one of another run not past ``since``
   (an earlier run's, the places going on across a restart: review 86), else 0 (review 83: a
   status forged naming another run, read before the STOP, no longer ends the hold at the
   station's next status of its own run; a station that counts from 1 in each run, ``since``
   0: every place of its new run came after what the halt was asked against). Who published a
   status is not known: MQTT 5 gives a subscriber no publisher's identity, and a user property
   the station added would be forged as easily as the payload. So a client allowed to publish
   on the station's topics can still end a hold (a status showing the turn ended, or a later
   one) or make a stamp high within what the station's next status confirms; the broker's ACL
   (only the station's bridge may publish there) is the guard (docs/remote.md). (The same halt
   sent again by this link keeps its stamp; pressed again, it is stamped anew; a rotator's
   status read before the remote knew the rotator, its replay on subscribing, counts too:
   ``read_status``). A status as published (``live``; remote/run.py's ``_proof`` reads it)
   then judges it: a STOP is done (no longer held) once a status shows no turn (a target, the
   azimuth's or the elevation's, tracking or following: review 83, an az/el rotator's
   elevation target, its azimuth's arrived, read as none) and the rotor at rest (review 83: a
   box turning on to its old target under a restarted bridge that follows unasked moves shows
   no target, and its first reading says ``braking``; a rotor coasting to a stop ends the hold
   once still), or a turn from a place after the stamp (a newer command, this remote's or
   another front end's, wins: review 79, an old STOP sent again stopped Home Assistant's later
   turn); a lock ON is done once a status shows the lock ON, or a lock word after the stamp (a
   lock OFF at the tower: review 79, undone by an old lock ON). A status of another run than
   the stamp's (the station's bridge restarted) ends nothing by itself: what the restart kept
   stands at its own place, kept with it in the state file (review 83: the lock outlives a
   restart; a lock ON held over one, dropped at the new run's first status, left the station
   unlocked; a STOP held over one, dropped so, let the box turn on to the target it was
   pressed against), and is judged against the stamp as any (review 86: with the places
   counted from 1 in each run, the stamp counted as 0 in the new run and what it kept as from
   place 0, so a lock OFF at the tower, or Home Assistant's turn, taken after the held halt
   while this remote was away and kept over the restart, was undone by it). A status that does
   not know a state (``lock_unknown``; the motion: ``offline`` or ``unknown``, a run's first
   status) judges nothing. What was asked against still standing (the turn, the lock OFF, from
   a place not after the stamp) means the station never took the halt, if its bridge connected
   again since: the halt is ``due`` once the station's bridge says ``online`` (as published,
   or replayed to this link's new connection: review 79, a broker restart; either way a new
   connection of the station's may have lost it), and the first live status after that showing
   what it was asked against still standing sends it again at the station's next live
   heartbeat (rule 6's ``_unheard``, and before any later command), once per ``online`` (the
   rate limit: on one connection the broker hands the station what it took in order, so a
   status before the halt came says nothing). A held halt found done while it waits to go
   again does not go. A later move ends no hold (review 79: a move the station never had, or
   one the broker never took, proved nothing; and a move never overrides a lock ON); a later
   word on a halt's own topic that the broker took (a lock OFF after a lock ON) is this
   remote's last word there and ends it. A station's bridge whose status carries no ``order``
   (an older version) gets no hold: its halts go as before rule 10.
"""

from __future__ import annotations

import contextlib
import logging
import math
import socket
import ssl
import struct
import sys
import threading
import time
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any

from paho.mqtt.enums import MQTTErrorCode
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties
from paho.mqtt.reasoncodes import ReasonCode
from paho.mqtt.subscribeoptions import SubscribeOptions

from bridge.core.errors import RefusalCode, Refused
from bridge.interfaces.mqtt.connection import LOGIN_REFUSED, TAKEOVER_FIRST_S, Connection
from bridge.interfaces.mqtt.heartbeat import EXPIRY as STAMP_EXPIRY
from bridge.interfaces.mqtt.heartbeat import (
    MAX_EXPIRY_S,
    NAMELESS,
    SENT,
    STATION,
    Stamp,
    StationClock,
    parse_beat,
    station_of,
)
from bridge.settings.mqtt import MqttSettings

log = logging.getLogger(__name__)

COMMAND_QOS = 1  # rule 2
ACK_WAIT_S = 1.0  # rule 7
AGAIN_SEEN_MAX_S = 30.0  # rule 8: a halt kept longer is stamped when sent again
HALT_READERS = 256  # rule 8: the sources whose last halt's stamp is kept
# rule 10: the station's runs whose places seen are kept, by halt, and the places of each (a
# forger flooding more crowds the station's own out: the stamp then counts as 0, docs/remote.md)
LEDGER_RUNS = 4
LEDGER_PLACES = 32
NOT_CONNECTED = "not connected to the station's broker"
NOT_HEARD = (
    "the station's bridge is not heard (no heartbeat): nothing sent (a bridge older than this "
    "remote sends none)"
)
SEEN_BEFORE_HALT = (
    "seen before a STOP or lock ON sent from here that came first (a client, or a computer, "
    "that held it up): not carried out; send it again"
)
MAYBE_BEFORE_HALT = (
    "it may have come before a STOP or lock ON another program sent from here a moment "
    "earlier (the two were read apart, so their order is not known): not carried out; send it "
    "again"
)
KEPT = (
    f"{NOT_CONNECTED}: not delivered yet (the rotor may still be turning); the stop is kept "
    "and sent first on reconnect"
)
NO_MQTT5 = "Unsupported protocol version"  # 0x84: NATS, aedes, mosquitto set to 3.1.1 only


@dataclass(frozen=True)
class Standing:
    """Rule 10: a station's status of one rotator, on the halts to it: its run and the newest
    place it shows every command up to (``taken``), and for each halt (topic, payload) the
    place of the state that halt ends if it still stands (the turn a STOP ends, the lock OFF
    a lock ON ends), else None."""

    run: str
    taken: int
    halts: tuple[tuple[tuple[str, bytes], int | None], ...]
    unsaid: frozenset[tuple[str, bytes]] = frozenset()  # halts this status cannot judge
    since: int = 0  # no place of an earlier run is past it (core/model.py Order; 0: none kept)


def _ledger_put(ledger: dict[str, list[int]], run: str, taken: int) -> None:
    """Rule 10: ``taken`` noted among the places seen of ``run``; at most LEDGER_RUNS runs (the
    one noted longest ago goes) and LEDGER_PLACES places each (the lowest goes: the station's
    ``taken`` only grows, and a later status confirms places up to its own)."""
    places = ledger.pop(run, [])
    ledger[run] = places  # (the run noted last, last)
    if taken not in places:
        places.append(taken)
        places.sort()
        del places[:-LEDGER_PLACES]
    while len(ledger) > LEDGER_RUNS:
        del ledger[next(iter(ledger))]


def held_stamp(before: dict[str, tuple[int, ...]], run: str, taken: int, since: int = 0) -> int:
    """Rule 10: a held halt's stamp as a status of ``run`` showing every command up to
    ``taken``, and no place of an earlier run past ``since``, judges it: the newest place
    seen before the halt was asked that this status confirms: one of that run not past its
    ``taken`` (the station's own never goes back in a run, so a place seen past it was not
    the station's), or one of another run not past ``since`` (an earlier run's: review 86,
    places go on across restarts); 0 if none (a restart since, of a station that counts from
    1 in each run: every place of the new run came after what the halt was asked against)."""
    floor = min(since, taken)
    return max(
        (p for r, places in before.items() for p in places if p <= (taken if r == run else floor)),
        default=0,
    )


@dataclass
class _Held:
    """Rule 10: a halt the broker took, held: what it went with, the places of each run of the
    station's that its rotator's statuses showed before it was asked (``held_stamp`` makes
    its stamp of them), whether the station's bridge said ``online`` since (``due``), and
    whether it waits in ``_unheard`` to go again."""

    props: Properties
    before: dict[str, tuple[int, ...]]
    due: bool = False
    queued: bool = False


class RemoteLink(Connection):
    """Subscribes ``filters``; hands every message to ``on_message`` (paho's thread);
    ``on_change`` is called whenever the connection comes up or goes down."""

    FIGHT_BACKOFF_MAX_S = TAKEOVER_FIRST_S  # (connection.py rule 7: it carries the stops, rule 6)

    def __init__(
        self,
        settings: MqttSettings,
        client_id: str,
        filters: list[str],
        on_message: Callable[[str, bytes, bool], None],
        on_change: Callable[[], None] = lambda: None,
        last_word: Callable[[str, bytes], bool] = lambda topic, payload: False,
        heartbeat: str | None = None,
        station_state: str | None = None,
        proof: Callable[[str, bytes], Standing | None] = lambda topic, payload: None,
        clock: Callable[[], float] = time.monotonic,
        ack_wait_s: float = ACK_WAIT_S,
    ) -> None:
        def handle(
            topic: str, payload: bytes, retain: bool, _operator: str | None, _stamp: Stamp | None
        ) -> None:
            on_message(topic, payload, retain)  # a station's state carries no operator

        super().__init__(
            settings, client_id, subscriptions=filters, on_message=handle, reconnect_max_s=10
        )
        self._heartbeat = heartbeat
        self._station_state = station_state  # rule 10: B/bridge/state
        self._proof = proof  # rule 10
        self._auto = False  # rule 1: never steps down to MQTT 3.1.1
        self._send_lock = threading.Lock()
        self._on_change = on_change
        self._ever_up = False
        self.failure: str | None = None  # rule 5: why the last attempt failed, said in one line
        self.fatal = False  # rule 5: ... and trying again will not mend it
        self._last_word = last_word  # rule 6
        self._held: list[tuple[str, bytes, Properties]] = []  # rule 6: for the next connection
        # rule 6: sent again on this connection, and once more when the station is heard on it
        self._unheard: list[tuple[str, bytes, Properties]] = []
        # rule 10: halts the broker took that the station has not yet shown done or outdated
        self._unproven: dict[tuple[str, bytes], _Held] = {}
        # rule 10: by halt (topic, payload), the places its rotator's statuses showed taken, by
        # the station's run (``_ledger_put``): what a halt asked now is stamped from
        self._orders: dict[tuple[str, bytes], dict[str, list[int]]] = {}
        # rule 8: the latest stamp a halt went out with, by topic (its time, its station)
        self._halt_stamps: dict[tuple[str, Hashable | None], tuple[float, str]] = {}
        # rule 8: each halt's latest asking (its topic, payload): when it was seen, its source
        self._halt_seen: dict[tuple[str, bytes], tuple[float, Hashable | None]] = {}
        # rule 8: the latest seen time of a halt sent or kept, by topic, from any source
        self._halt_latest: dict[str, float] = {}
        # rule 8: the latest read times of halts sent or kept, by topic: (read, its source),
        # two sources at most (the latest read, and the latest of any other source's)
        self._halt_read: dict[str, list[tuple[float, object]]] = {}
        self._clock = clock
        self.station_clock = StationClock(clock)  # rule 8
        self._ack_wait_s = ack_wait_s
        self._acks = threading.Condition()  # rule 7: PUBACKs, the connection's generation
        self._acked: dict[int, ReasonCode | None] = {}  # mid -> the PUBACK's reason
        self._unawaited: set[int] = set()  # held stops resent: nobody waits for their PUBACK
        self._generation = 0  # one more on every connection opened or closed
        self._reset_generation = -1  # the connection rule 7 reset
        self.resets = 0  # rule 7: how many, for the operator's diagnostics and the tests
        self._client.on_publish = self._on_publish

    @property
    def up(self) -> bool:
        return self.connected.is_set()

    def start(self) -> None:
        self._connect()

    def stop(self) -> None:
        self._stopping = True
        self._disconnect()

    def send(
        self,
        topic: str,
        payload: str,
        operator: str,
        expiry_s: int,
        check: Callable[[], None] | None = None,
        *,
        until_heard: bool = False,
        seen_s: float | None = None,
        after: tuple[str, ...] = (),
        reader: Hashable | None = None,
        read_s: float | None = None,
    ) -> None:
        """Rules 2, 3, 7 and 8: acknowledged by the broker, or Refused and never sent later
        (a stop excepted: rule 6). ``check``, if given, is asked under the send lock right
        before the command is handed to paho, and may raise Refused (rule 9): a command with
        one is a move (remote/rotator.py sends every move with one). ``until_heard``
        (a halt sent while the station's bridge is not heard): sent again at the first live
        heartbeat from then on (rule 6). ``seen_s`` (when it was seen, on this link's clock):
        stamped then; a move never before the latest stamp a halt on one of ``after`` (its
        rotator's halt topics) went out with from the same source, ``reader`` (its connection or
        port; None: not known, no halt lifts it), and refused if seen before a halt on one of
        ``after`` that this remote sent or kept, or, if that halt is another reader's, before
        it was read (rule 8). ``read_s`` (a halt's): the latest its bytes can have come, where
        the reader knows it (a kernel's datagram stamp); None: now, when it is sent."""
        halt = self._last_word(topic, payload.encode())
        props = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]  # paho untyped
        props.MessageExpiryInterval = expiry_s
        now = self._clock()  # (a halt handed over now was read by now: rule 8)
        with self._send_lock:
            if halt:  # rule 8: sent again, stamped with when it was (last) seen
                seen = now if seen_s is None else seen_s
                self._halt_seen[topic, payload.encode()] = seen, reader
                self._halt_latest[topic] = max(seen, self._halt_latest.get(topic, seen))
                self._note_read(topic, max(seen, now if read_s is None else read_s), reader)
            if not self.up and halt:  # down, or being reset: rule 6
                props.UserProperty = [("operator", operator)]
                self._keep(topic, payload.encode(), props)
                raise Refused(RefusalCode.OFFLINE, KEPT)
            if not self.up:
                raise Refused(RefusalCode.OFFLINE, NOT_CONNECTED)
            if not halt and seen_s is not None:  # rule 8: seen before a halt sent from here
                if any(seen_s < self._halt_latest.get(t, seen_s) for t in after):
                    raise Refused(RefusalCode.STALE, SEEN_BEFORE_HALT)
                if any(seen_s < self._read_besides(t, reader) for t in after):
                    raise Refused(RefusalCode.STALE, MAYBE_BEFORE_HALT)  # (another reader's)
            # rule 8: a halt's if it has one; when it was seen, if that is said; a move's
            # never before its rotator's last halt's
            keys = [] if reader is None else [(t, reader) for t in after]  # (None: unknown)
            latest = [self._halt_stamps[k] for k in keys if k in self._halt_stamps]
            floor = None if halt else max(latest, default=None)
            stamped = self.station_clock.stamp(expiry_s, seen_s, floor)
            if stamped is None and not halt:
                raise Refused(RefusalCode.OFFLINE, NOT_HEARD)
            stamp = [] if stamped is None else stamped.properties()
            props.UserProperty = [("operator", operator), *stamp]
            if check is not None:
                check()  # rule 9
            if not halt and self._unheard:  # rule 6: the halts kept go before a later word
                self._send_unheard_before(topic, moves=check is not None)
            info = self._client.publish(
                topic, payload, qos=COMMAND_QOS, retain=False, properties=props
            )
            if info.rc != MQTTErrorCode.MQTT_ERR_SUCCESS:
                self._forget_unsent(refused_mid=info.mid)  # paho kept it for later: rule 3
                if halt:
                    self._keep(topic, payload.encode(), props)
                    raise Refused(RefusalCode.OFFLINE, KEPT)
                raise Refused(RefusalCode.OFFLINE, NOT_CONNECTED)
            if halt and reader is not None:  # rule 8: no move its reader read after it is
                self._note_halt(topic, props, reader)  # stamped before it
            if halt and until_heard:  # rule 6: maybe nobody subscribed to it yet
                if not any(t == topic and p == payload.encode() for t, p, _ in self._unheard):
                    self._unheard.append((topic, payload.encode(), props))
            if halt:  # rule 10: until the station shows it done, or outdated
                self._unprove(topic, payload.encode(), props, asked=True)
            generation = self._generation
        self._await_ack(topic, info.mid, generation, halt)
        if not halt:  # rule 10: a later word on a halt's topic the broker took is the last
            with self._send_lock:
                for key in [k for k in self._unproven if k[0] == topic]:
                    self._unproven_end(key)

    def _await_ack(self, topic: str, mid: int, generation: int, halt: bool) -> None:
        """Rule 7: returns once the broker acknowledged ``mid``; else Refused."""
        with self._acks:
            self._acks.wait_for(
                lambda: mid in self._acked or self._generation != generation, self._ack_wait_s
            )
            acked = mid in self._acked
            reason = self._acked.pop(mid, None)
        again = "; the stop goes again first thing on the next connection" if halt else ""
        if acked:
            if reason is not None and reason.is_failure:
                raise Refused(
                    RefusalCode.INVALID,
                    f"the station's broker refused it ({reason}): may this user publish "
                    f"{topic}? (the broker's ACL)",
                )
            return
        if self._reset(generation):
            raise Refused(
                RefusalCode.OFFLINE,
                f"the station's broker did not acknowledge it within {self._ack_wait_s:g} s "
                f"(a stalled link): connection reset, nothing sent later{again}",
            )
        raise Refused(
            RefusalCode.OFFLINE,
            "the connection to the station's broker dropped before it acknowledged the "
            f"command: not sent again{again}",
        )

    def _reset(self, generation: int) -> bool:
        """Rule 7: the connection ``generation`` shut now, unless it is gone already (False)."""
        with self._send_lock:
            if self._generation != generation or not self.up:
                return self._reset_generation == generation  # another send reset it
            self._reset_generation = generation
            self.resets += 1
            self.connected.clear()  # no send goes into the dying connection
            sock = self._client.socket()
        log.warning(
            "the station's broker did not acknowledge a command within %g s: the link stalls; "
            "resetting the connection (what it holds unsent is dropped) and connecting again",
            self._ack_wait_s,
        )
        abort(sock)
        return True

    def _on_publish(
        self,
        client: object,
        userdata: object,
        mid: int,
        reason_code: ReasonCode | None,
        properties: Properties | None,
    ) -> None:
        """paho's thread: a PUBACK (rule 7)."""
        with self._acks:
            if mid in self._unawaited:
                self._unawaited.discard(mid)
                return
            self._acked[mid] = reason_code
            self._acks.notify_all()

    def _next_generation(self) -> None:
        with self._acks:
            self._generation += 1
            self._acked.clear()
            self._unawaited.clear()
            self._acks.notify_all()

    def _forget_unsent(self, refused_mid: int | None = None) -> None:
        """Rules 3 and 6: paho's queue of unacknowledged messages emptied, the last words among
        them held for the next connection (caller holds _send_lock), ahead of any kept since
        the connection went down: they were sent before those were asked (the close can be
        handled after a halt asked meanwhile was kept)."""
        dropped, unacknowledged = 0, []
        for m in self._client.drop_out_messages():  # paho 2.2's own, as client.py uses
            payload, props = bytes(m.payload), m.properties  # send gave it its properties
            if m.mid != refused_mid and props is not None and self._last_word(m.topic, payload):
                unacknowledged.append((m.topic, payload, props))
                log.warning(
                    "%s: not acknowledged by the broker before the connection dropped: it may "
                    "not have reached the station; sent again on the next connection",
                    m.topic,
                )
            else:
                dropped += 1
        unheard, self._unheard = self._unheard, []  # rule 6: sent before the station was heard
        again = {(topic, payload) for topic, payload, _ in unacknowledged}  # (once, however
        unheard = [h for h in unheard if (h[0], h[1]) not in again]  # often it is pressed)
        again |= {(topic, payload) for topic, payload, _ in unheard}
        kept = [h for h in self._held if (h[0], h[1]) not in again]
        self._held = unheard + unacknowledged + kept
        if dropped:
            log.warning(
                "%d command(s) not acknowledged by the broker dropped, never resent", dropped
            )

    def _keep(self, topic: str, payload: bytes, props: Properties) -> None:
        """Rule 6: a halt that could not go now goes first on the next connection, once
        (caller holds _send_lock)."""
        if any(t == topic and p == payload for t, p, _ in self._held):
            return  # the same stop pressed again: one is enough
        self._held.append((topic, payload, props))
        log.warning(
            "%s: not connected to the station's broker: kept, sent first on the next connection",
            topic,
        )

    def _resend_held(self) -> None:
        """Rule 6, on the new connection before ``send`` may run (caller holds _send_lock);
        each goes once more when the station is heard on it (``_resend_unheard``)."""
        held, self._held = self._held, []
        for topic, payload, props in held:
            log.warning("%s sent again (not acknowledged on the last connection)", topic)
            self._publish_unawaited(topic, payload, props)
        self._unheard = held

    def _resend_unheard(self, beat: float, station: str | None) -> None:
        """Rule 6, paho's thread at a live heartbeat (``beat``: its time; ``station``: the
        process it names), the station's clock reckoned from it first, under the send lock
        (rule 8: no other command can be stamped before these go)."""
        with self._send_lock:
            self.station_clock.heard(beat, station)
            unheard, self._unheard = self._unheard, []
            for topic, payload, props in unheard:
                log.warning("%s sent again now that the station's bridge is heard", topic)
                self._publish_unawaited(topic, payload, props)

    def _send_unheard_before(self, topic: str, *, moves: bool) -> None:
        """Rule 6: a command asked after the halts kept for the station's return goes after
        them (caller holds _send_lock): they go now, those on its own topic excepted, which
        it overrides (a lock OFF after a lock ON). Before a move (``moves``: one sent with a
        ``check``, rule 9) that is their last time; before what never moves (tracking off,
        a lock OFF) they stay kept for the station's first heartbeat: that command may go to
        nobody as they did, and it ends no halt's wait."""
        unheard, self._unheard = self._unheard, []
        for kept in unheard:
            kept_topic, payload, props = kept
            if kept_topic != topic:
                log.warning("%s sent again before a later command", kept_topic)
                self._publish_unawaited(kept_topic, payload, props)
                if not moves:
                    self._unheard.append(kept)

    def _publish_unawaited(self, topic: str, payload: bytes, props: Properties) -> None:
        """A kept halt sent again (caller holds _send_lock): nobody waits for its PUBACK.
        Rule 8: stamped with when it was last asked (seen), as its source's moves are, by the
        reckoning now; its stamp's ``expiry`` lengthened by the time it was kept, so that the
        station takes it as sent then (up to its HALT_STAMP_MAX_S); kept longer than
        AGAIN_SEEN_MAX_S, stamped now; with no reckoning, as it was. Noted for its source,
        unless stamped now."""
        seen, reader = self._halt_seen.get((topic, payload), (None, None))
        now = self._clock()
        if seen is not None and not 0.0 <= now - seen <= AGAIN_SEEN_MAX_S:
            seen = None  # (the station would count it from when it came: stamped now)
        expiry = int(getattr(props, "MessageExpiryInterval", 0))  # (paho's: set dynamically)
        kept_s = 0 if seen is None else math.ceil(now - seen)
        stamp = self.station_clock.stamp(min(expiry + kept_s, MAX_EXPIRY_S), seen)
        if stamp is not None:
            props = _stamped(props, stamp)
        info = self._client.publish(topic, payload, qos=COMMAND_QOS, retain=False, properties=props)
        self._unprove(topic, payload, props, asked=False)  # rule 10: still held
        if reader is not None and seen is not None:  # (stamped now: its reader's floor not
            self._note_halt(topic, props, reader)  # lifted to that, review 30)
        with self._acks:
            self._unawaited.add(info.mid)

    def _unprove(self, topic: str, payload: bytes, props: Properties, *, asked: bool) -> None:
        """Rule 10 (caller holds _send_lock): a halt the broker takes is held, stamped with the
        newest place its rotator's status showed taken; ``asked`` (pressed now, not sent again
        by this link): stamped anew. With no place seen (a station's bridge that publishes no
        ``order``) it is not held."""
        key = (topic, payload)
        held = self._unproven.get(key)
        if held is not None and not asked:
            held.props = props
            return
        ledger = self._orders.get(key)
        if not ledger:
            self._unproven_end(key)
            return
        if held is not None:
            self._unproven_end(key)
        self._unproven[key] = _Held(props, {run: tuple(p) for run, p in ledger.items()})

    def _unproven_end(self, key: tuple[str, bytes]) -> None:
        """Rule 10 (caller holds _send_lock): ``key``'s halt no longer held; not sent again
        either, if it waits to be."""
        held = self._unproven.pop(key, None)
        if held is not None and held.queued:
            self._unheard = [h for h in self._unheard if (h[0], h[1]) != key]

    def _standing(self, standing: Standing, live: bool) -> None:
        """Rule 10, paho's thread: a status of the station's (``live``: as published, not a
        replay). Its order is noted for what a halt asked from now is stamped from; live, it
        ends each held halt of its rotator whose state no longer stands, or stands from a
        place after the halt's stamp (``held_stamp``: in a run not seen before the halt, after
        0: a restart since); and a
        held halt whose state still stands from a place not after its stamp, once the
        station's bridge said ``online`` since, goes again at its first live heartbeat (rule
        6). A status that cannot say (``unsaid``: the lock not known yet) judges nothing."""
        with self._send_lock:
            for key, place in standing.halts:
                _ledger_put(self._orders.setdefault(key, {}), standing.run, standing.taken)
                held = self._unproven.get(key)
                if held is None or not live or key in standing.unsaid:
                    continue
                stamp = held_stamp(held.before, standing.run, standing.taken, standing.since)
                if place is None or place > stamp:
                    self._unproven_end(key)
                elif held.due:
                    held.due = False
                    if not any((t, p) == key for t, p, _ in self._unheard):
                        log.warning(
                            "%s: the station's bridge connected again and its status shows "
                            "what this ended still standing: sent again once it is heard",
                            key[0],
                        )
                        self._unheard.append((key[0], key[1], held.props))
                        held.queued = True

    def read_status(self, topic: str, payload: bytes) -> None:
        """Rule 10: a status read before ``proof`` knew its rotator (the remote finds its
        rotators after it subscribed: their replayed statuses came first), taken as replayed:
        its order is what a halt asked from now is stamped with; it judges no held halt."""
        standing = self._proof(topic, payload)
        if standing is not None:
            self._standing(standing, live=False)

    def _station_back(self) -> None:
        """Rule 10, paho's thread: the station's bridge says ``online`` (as published, or
        replayed to this link's new connection: either way it may have connected again since
        a held halt went, a clean session): each held halt is judged again by the station's
        next live status of its rotator."""
        with self._send_lock:
            for held in self._unproven.values():
                held.due = True

    def _note_read(self, topic: str, read: float, reader: Hashable | None) -> None:
        """Rule 8: a halt on ``topic`` from ``reader`` read by ``read`` (caller holds
        _send_lock). Two sources are kept, the latest read first: the latest of every source
        but any one is among them. An unknown source (None) is none other's: its own."""
        who: object = object() if reader is None else reader
        kept = self._halt_read.get(topic, [])
        read = max([read] + [r for r, w in kept if w == who])
        kept = sorted([(r, w) for r, w in kept if w != who] + [(read, who)], key=lambda k: -k[0])
        self._halt_read[topic] = kept[:2]

    def _read_besides(self, topic: str, reader: Hashable | None) -> float:
        """Rule 8: the latest read time of a halt on ``topic`` from a source other than
        ``reader`` (None: every halt's), -inf if none (caller holds _send_lock)."""
        for read, who in self._halt_read.get(topic, ()):
            if reader is None or who != reader:
                return read
        return -math.inf

    def _note_halt(self, topic: str, props: Properties, reader: Hashable | None) -> None:
        """Rule 8: the latest stamp a halt on ``topic`` from ``reader`` (its source) went out
        with, if any (caller holds _send_lock): no move of that source is stamped before it
        (``send``'s ``after``)."""
        stamp = Stamp.of_properties(list(getattr(props, "UserProperty", None) or []))
        sent = None if stamp is None else stamp.sent_unix()
        if stamp is None or sent is None:
            return
        station = stamp.station or NAMELESS
        noted = self._halt_stamps.get((topic, reader))
        if noted is None or noted[1] != station or noted[0] < sent:
            self._halt_stamps.pop((topic, reader), None)  # (the newest last: rule 8's bound)
            self._halt_stamps[topic, reader] = sent, station
            if len(self._halt_stamps) > HALT_READERS:
                del self._halt_stamps[next(iter(self._halt_stamps))]

    # -- Connection's hooks (paho's thread) --------------------------------------------------
    def _on_message(self, client: Any, userdata: Any, msg: Any) -> None:
        """Rule 8: a live heartbeat says the station's time and, in its user property
        ``station``, which process of the station's bridge beats (heartbeat.py rule 7); then
        every message goes on to the handler as the bridge's would."""
        if msg.topic == self._heartbeat and not msg.retain:  # only a live one says the time
            try:  # (a forged beat must not kill paho's thread: connection.py rule 5)
                props = getattr(msg, "properties", None)
                station = station_of(getattr(props, "UserProperty", None) or [])
                beat = parse_beat(bytes(msg.payload))
                if self._unheard:  # rule 6: the station's bridge is on this connection now
                    self._resend_unheard(beat, station)
                else:
                    self.station_clock.heard(beat, station)
            except ValueError:
                pass  # no time: no beat
            except Exception:
                log.exception("error reading the station's heartbeat")
        else:  # rule 10
            try:
                if msg.topic == self._station_state:
                    if bytes(msg.payload) == b"online" and self._unproven:
                        self._station_back()
                elif (standing := self._proof(msg.topic, bytes(msg.payload))) is not None:
                    self._standing(standing, live=not msg.retain)
            except Exception:
                log.exception("error reading the station's word on its halts")
        super()._on_message(client, userdata, msg)

    def _refused(self, reason: str) -> None:
        if self._ever_up:
            super()._refused(reason)
            return
        login = reason in LOGIN_REFUSED
        old = reason == NO_MQTT5
        if login:
            self.failure = (
                f"the broker refused the login ({reason}): check mqtt.username and "
                "mqtt.password_file"
            )
        elif old:
            self.failure = f"this broker does not speak MQTT 5 ({reason}), which the remote needs"
        else:
            self.failure = f"the broker refused the connection ({reason})"
        self.fatal = login or old  # trying again cannot mend either
        log.debug("%s", self.failure)

    def _closed_early(self, reason: str) -> None:
        if self._ever_up or self._stopping:
            super()._closed_early(reason)
            return
        self.failure = (
            f"the broker closed the connection before accepting it ({reason}): it answered, but "
            "either it does not speak MQTT 5, which the remote needs (RabbitMQ and amqtt close "
            "the connection so), or its access rules refuse this client id or user"
        )
        log.debug("%s", self.failure)

    def _unanswered(self, waited: str) -> None:
        if self._ever_up or self._stopping:
            super()._unanswered(waited)
            return
        self.failure = (  # (connection.py rule 6: neither a refusal nor a close of the broker's)
            f"the broker did not answer the connection {waited}: it took the connection and "
            "then said nothing (stalled or overloaded, or its host or the network holding its "
            "packets)"
        )
        log.debug("%s", self.failure)

    def _failed(self) -> None:
        if self._ever_up or self._stopping:
            super()._failed()
            return
        exc = sys.exc_info()[1]  # paho calls back inside its `except OSError`: it says why
        if isinstance(exc, ssl.SSLError):
            # "[SSL: CERTIFICATE_VERIFY_FAILED] certificate verify failed: ... (_ssl.c:1006)"
            why = str(exc).split("] ", 1)[-1].split(" (_ssl.c")[0]
            self.failure = (
                f"TLS handshake failed: {why}: check mqtt.tls.ca_file (the authority that "
                "signed the broker's certificate) and mqtt.host (the name it was issued for)"
            )
            self.fatal = True
        else:
            self.failure = str(exc or "no answer")
        log.debug("%s", self.failure)

    def _filters(self) -> list[tuple[str, Any]]:
        """Rule 4: retain-as-published off (the retain flag then means replayed)."""
        state = SubscribeOptions(qos=0, retainAsPublished=False)
        return [(topic, state) for topic in self._subscriptions]

    def _opened(self, client: object) -> None:
        self._ever_up = True
        self.failure, self.fatal = None, False
        with self._send_lock:  # rule 6: the held last words first
            self._next_generation()
            self._resend_held()
            self.connected.set()
        self._on_change()

    def _closed(self, was_up: bool, reason_code: ReasonCode) -> bool:
        with self._send_lock:  # a send under way finishes first, then its message goes too
            self._forget_unsent()
            ours = self._reset_generation == self._generation  # rule 7: said already
            self._next_generation()
            self.station_clock.forget()
        self._on_change()
        if self._stopping or ours:  # our own goodbye or reset: no takeover evidence
            return False
        return super()._closed(was_up, reason_code)


def abort(sock: object) -> None:
    """Rule 7: shut a stalled connection's socket from any thread: paho's loop reads its end and
    connects again; closed with a reset (SO_LINGER 0), so the kernel drops the bytes it still
    held for the broker instead of delivering them when the link recovers."""
    if not isinstance(sock, socket.socket):
        return
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    with contextlib.suppress(OSError):
        socket.socket.shutdown(sock, socket.SHUT_RDWR)  # the descriptor's, TLS or not


def _stamped(props: Properties, stamp: Stamp) -> Properties:
    """Rule 8: a kept halt's properties with ``stamp`` in place of the stamp it had; its
    message expiry and operator as they were."""
    expiry = int(getattr(props, "MessageExpiryInterval", 0))  # (paho's: set dynamically)
    stamp_keys = (SENT, STAMP_EXPIRY, STATION)
    kept = [(k, v) for k, v in getattr(props, "UserProperty", None) or [] if k not in stamp_keys]
    fresh = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]  # paho untyped
    fresh.MessageExpiryInterval = expiry
    fresh.UserProperty = [*kept, *stamp.properties()]
    return fresh
