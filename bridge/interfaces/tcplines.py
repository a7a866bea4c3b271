"""The TCP side shared by the text front ends (rotctld, GS-232, Easycomm, DCU-1): one listener per
rotator and protocol, one thread per client, every reply in one send, and a budget per client so
that no client, nor all of them together, can starve the serial-lines thread of the GIL.

What a client's bytes mean is not decided here: each client gets a fresh ``LineSession`` from the
front end (its parser and its commands onto the judge); this module owns the sockets.

Rules:
1. Each reply the session returns goes out in one ``sendall`` (Gpredict reads ``p`` with a single
   recv(); a GS-232 client reads one line).
2. A connection that speaks HTTP is closed at once with a warning and nothing it sent runs: its
   first line is held until complete and may not be an HTTP request line, and no line may be an
   HTTP header (``Host: ...``). A text protocol parses any bytes as commands, so a web page open
   on the shack PC could otherwise turn the antenna through a loopback port. Bytes that are a
   whole command on their own and move nothing (``singles``: a DCU-1's ``V`` and option letters,
   which no end follows; rotctld's ``S`` and ``p``) go at once while the first line is nothing
   else, so such a program is answered when it asks (and a stop carried out); the line they
   begin is still held and judged whole.
3. A client is disconnected when it sends nothing for the idle timeout (300 s by default), or
   leaves a command unfinished for 60 s (one byte a second would hold a slot for ever).
   A new client always gets in to send its stop: when every slot is taken (``max_clients``),
   a client is dropped to make room, never the newcomer turned away, in this order
   (``_Client.rank``; each step a way round the order before it that an attack pass or a
   review found, each keeping every stop out of a full port of local programs under their
   budgets, or getting the one quiet program, Gpredict, dropped in their place): one paused
   over its budget (rule 5), the longest first, whatever it sent unread (a stop behind its
   flood waited behind it anyway); one whose reply has waited SEND_STALL_S to be sent (it
   reads none: its thread waits in its send, its lines unread); one that has had a command
   half received for more than PENDING_GRACE_S in all and more than SPLIT_SHARE of its time
   connected (``splitting``: a program's command comes whole, or split for milliseconds), the
   most of its time first; then of those at rest (no command half received, none unread) the
   newest that never finished a command in PENDING_GRACE_S, then one idle for IDLE_S (the
   longest first), then the newest established connection (a program connected before a
   flood is kept; the one idle longest was Gpredict, polling once a second among chattier
   clients); then one just come that has sent no command yet (a review: each later
   connection dropped it before the stop it was opened for came), of one address only the
   YOUNG_KEPT newest (an attack pass: all of them were, and a silent connection every 0.1 s
   dropped Gpredict again and again, with the STOP it had sent; the rest rank as never
   finished a command); then one with a command half received now, the one whose half came
   first (a program's is milliseconds old); last one with a complete command line not read
   yet or being read (a stop, maybe). A client
   dropped carries out nothing more of what it sent (a review: a flood dropped for the
   operator read on its queued targets after the operator's stop). Drops are logged at most
   once per 10 s, with a count and why.
   A peer
   address other than loopback holds at most ``max_per_peer`` slots (a quarter by default), and
   past that makes room among its own clients the same way, so one host's connections cannot
   fill the port for the others. Loopback has no such share: every program on the host is
   loopback (127.0.0.0/8 and ::1 count as one address, here and in rule 5: a program may
   bind any of them, an attack pass took 500), so a share would be a limit on the shack's
   own programs; there the make-room rule is what lets the operator in.
4. ``listen`` takes the address before anything else starts, and its OSError names the front end,
   the rotator, the address and the setting to change.
5. Nothing a client sends can starve a stop (docs/architecture.md rule 12), by construction: at
   most ``max_clients`` threads a port, each started only for a connection alive when accepted
   and within its peer address's ACCEPTS_S a second (a burst of as many). The accept loop takes
   every connection from the kernel at once (a backlog full of dead connections kept a real
   client waiting, or dropped it): a wake-up drains the kernel's queue (ACCEPT_BATCH at most),
   which is BACKLOG long, not Python's 128 (two threads connecting and closing as fast as they
   could kept 128 full: the kernel dropped the operator's handshake, and its retries got the
   stop in 1, 2 or 4 s later, 8 stops of 40; with 1,024 none of 160 took over 0.05 s,
   benchmarks/operator_stop_flood.py, 256 let 1 or 2 of 80 through a second late), nor the
   kernel's cap of 4,096: a program that connects from more threads than the loop can keep up
   with fills any queue, and a stop on a new connection waits behind all of it (an attack pass:
   four threads opening half-command connections, 4,096 of them ahead of the stop, up to 0.6 s;
   a queue full also drops their own handshakes, a second each, which is what holds such a
   program back, the sooner the shorter the queue: docs/performance.md); one its peer already
   closed is closed with no thread
   and no budget; one over its peer's budget waits in the accept loop, no thread, until the budget
   allows (oldest first), and is closed as soon as its peer leaves (one that sent bytes: when
   it is let in). One whose first commands (READ_BYTES of them, what its first read takes)
   hold a stop its session would carry out (what HttpGuard lets through, read by the front
   end's parser, ``halts``: rotctld's stops before a quit) goes at once, ahead of the budget,
   STOP_ACCEPTS_S a second from one address at most; any other command waits its turn (an
   attack pass: every complete line went ahead, and four threads connecting, asking ``C`` and
   closing started 8,726 client threads in 2 s, the serial-lines thread starved and a
   controller was called silent; the next pass: a request line before an ``S`` held a stop
   for the loop, never run, and a flood of them kept the operator's real one out). A waiting
   connection is read for a stop once per bytes it sent (the same pass: read again for every
   newcomer, 18 s of the accept thread's CPU in 20), one that sent part of a line again
   PARTIAL_POLL_S apart, not at every wake-up, and a newcomer's bytes are read once and parsed
   only if a command ends in them (an attack pass: beside a program holding 100 half-command
   connections and opening new ones as fast as it could, the kernel's queue full, a stop on a
   new connection waited behind it up to 0.2 s; a newcomer cost the loop 46 us of CPU, 33 now,
   and such a program's connect some 44 of its own, which its threads spread over the cores:
   the loop runs ahead of them, rule 10, and the queue is shorter, above). At most 4
   ``max_clients`` wait; past that the oldest without a stop unread is reset (the newest is
   the one an operator opened for a stop, maybe sent in two segments: an attack pass found it
   the first reset), and if every one holds a stop, their oldest for a newcomer that holds
   one too, the newcomer if its bytes hold none, and one that has sent nothing yet waits
   beyond the limit (one at most) for its bytes to decide (said at most once per LOG_S). A
   client's coming and going is logged at INFO CHATTER_S a second at most (a burst of
   CHATTER_BURST), the rest at DEBUG (an attack pass: 1,863 lines a second, past journald's
   limit, which then drops the service's warnings too), and a connection refused as HTTP at
   most once per LOG_S. accept()
   out of descriptors or buffers pauses the loop ERROR_PAUSE_S (said at most once per
   LOG_S); any error in the loop is logged so and the loop carries on. Over budget
   is not reset at once: on loopback the operator shares 127.0.0.1 with any flooding program, and
   would be turned away with it. So a flood of connect-and-close costs an accept and a close each
   and uses no one's budget. A wake-up reads at most READ_BYTES (so runs at most that many
   commands); each client has a budget (ratelimit.Budget) of bytes a second, each reply costing
   REPLY_COST more and each wake-up READ_COST more (clients sending a byte a segment, under
   their byte budgets, woke their threads 100,000 times a second: a whole core): over it,
   its thread sleeps in the kernel (an Event) and its bytes wait in TCP's buffers, said once
   (at most once per LOG_S a port). A client that sends MAX_UNFINISHED
   bytes without finishing a command (no command is near that long) is dropped and logged (at
   most once per LOG_S, with a count); the bytes are counted from the last command finished
   (a read that finishes one counts its own bytes at most), so commands sent back to back,
   however the reads cut them, never add up. A client that takes no reply for SEND_WAIT_S
   (its replies unread, the socket's buffers full) is dropped and logged. A well-behaved
   client's stop is read at its first wake-up: its budget is its own.
6. A command ends at CR or LF unless the front end names its own ends (``ends``: a DCU-1's
   ``;`` as well); rules 2, 3 and 5 look for those.
7. What its clients may hold of the process's descriptors is bounded and said (``most_held``:
   every slot, every waiting connection and the one beyond): the app makes room for the sum
   of every port's under the process's open-files limit (app.py rule 5).
8. A client that asks a question before the command it was run for, and waits for the answer
   first (Hamlib's network client, ``rotctl -m 2``: ``\\dump_state``, then ``S``), is answered
   while it waits over its address's budget (rule 5), by the accept loop, once a connection:
   the front end's ``greets`` says the answer when the bytes are that question alone (a
   question that moves nothing and reads nothing of the rotator's state as it changes). Its
   command then decides, as a newcomer's first bytes do: a stop goes at once. An attack pass:
   one thread on the host connecting, sending ``p`` and resetting, as fast as it could, kept
   every ``rotctl -m 2 S`` out, 6 of 6 (it waited for its answer behind the budget, its
   connection the oldest without a stop, reset to make room). When room must be made among
   the waiting (rule 5), those whose peer has already left (and whose bytes hold no stop) are
   closed first, looked for at most every SWEEP_S, and one answered so is reset only when
   every other without a stop is gone: answered, its command comes a round trip later, while
   a flood's connections came by the dozen (the first form of this rule still lost one
   ``S`` in three on a loaded machine, reset in that round trip). A peer gone by a reset
   with its bytes unread still peeks alive (the bytes come before the reset): its TCP state
   says so (Linux), and one whose bytes (READ_BYTES at most: one that sent more is kept as
   any, its thread reads them) hold no stop is closed when accepted, or swept once waiting;
   and one silent when last looked at is looked at again before it is reset for
   room: a question come since is answered (a CI run under load: a flood's connections, each
   sending ``p`` and resetting, filled the list and none was swept, and ``rotctl``, accepted
   before its question came, was the oldest and reset unanswered).
9. A STOP or lock ON is the last word over everything sent before it (docs/architecture.md
   rule 11), whichever interface brought it: a move a client sent before a rotator carried out
   a STOP or lock ON is not carried out, however late it is read (the budget, rule 5, leaves a
   flooding client's commands in the kernel for seconds): refused as the judge refuses a
   command a halt overtook (``since``, runtime/rotator.py; mailbox.py rule 10). A stream says
   nothing of when its bytes came, so the server looks: at the accept and at every read it
   reads the rotator's halt count (``halt_count``: the front end's, before the look, so that a
   halt between the two errs toward refusing) and then how much the connection has sent, read
   or not (what is read, plus FIONREAD). The bytes a command ends in were in the kernel at the
   first look that counted them; a halt counted after that look overtakes the command
   (``Fence``: its session hands its moves to the judge through it). The halts
   the connection's own session carried out meanwhile do not (a client's ``P 300 0``, ``S``,
   ``P 200 0`` read in one go turn the rotor to 200: the halt count each of its stops added is
   its own, ``Fence.halting``), each known by the count it made, told on the session's own
   thread (a cold review: an MQTT STOP counted while the client's own ``S`` was on its way was
   taken for its own, and a target sent before it was carried out). No read takes bytes past
   those the oldest look it has not read counted, so no read holds bytes from both sides of a
   halt (the same review: a target sent before a STOP, read with the poll sent after it, was
   carried out). The count is every front end's,
   another client's of the same port among them (``halts``: the remote's ``halts_for`` leaves
   out its own front end's, and a STOP from one rotctld client there did not fence another's
   move, a cold review), so the move is judged against it here, right before the judge, and
   refused as the judge refuses one (``STALE``). A look that finds the count as the look
   before it did only reaches further (one entry: SEEN_KEPT bounds halts, not reads), and
   the bytes a greeting took (rule 8) are not counted again (a cold review: rotctl's P after
   a STOP, its handshake answered while it waited, was refused as sent before the STOP). An
   attack pass: one client sent 24 KB of targets in one burst; an MQTT STOP stopped the rotor
   and the targets still in the kernel turned it on 5 s later, and after a lock ON and OFF one
   went out 0.08 s after the OFF. The rotator also tells the server right before it counts
   each halt (``halt_watchers``, core/haltwatch.py), and every connection is looked at then,
   at the count before it: a client's thread that sleeps over its budget (rule 5) and a
   connection waiting its turn in the accept loop make no look of their own meanwhile, and
   what they had sent by the halt was taken as sent after it (a second attack pass: a
   rotctld ``P`` sent 20 ms before an MQTT STOP, from a client paused over its budget or one
   waiting behind a flood of connections, turned the rotor 0.2 s after the stop). A look and
   the thread's read are one step under the connection's lock (a read waits for the bytes
   with a peek, then takes them at once), so no look counts bytes as both read and unread. A
   connection still in the kernel's queue has no look of its own until it is accepted: it is
   looked at then at the count when the queue was last found empty, by the accept loop or by
   the look before each halt (the same review: a target sent from the queue before a STOP was
   carried out); one that came after a halt the loop has not yet caught up with is refused
   too, which errs the safe way. Where the kernel cannot say what waits unread (Windows, no
   FIONREAD: the remote runs there) a look counts only what was read, so a move is judged at
   the count its own read's look read: this rule holds there only for what a read has taken.
   Each look also dates the bytes it counts (``Looks``: since when they may have been there,
   on the monotonic clock), and the fence hands that with each move and stop to the rotator
   (``Fence.submit``, ``seen_s``: front.py rule 3; the remote stamps with it, the station's
   judge ignores it): bytes the thread waited for (it found nothing unread before its peek)
   came when the peek woke; bytes that came while it did not watch (asleep over its budget,
   busy) came at any time since the connection was last known to hold nothing unread, the
   kernel's count at a look or, without FIONREAD, a read that took less than it asked for
   (review 24: on Windows the bytes past a read's first 64 were dated by that read's look,
   after a STOP they came before). A thread not run for a while after its peek woke (a busy
   computer) dates the bytes from when it ran; a connection's first bytes are dated from its
   accept (those sent while it waited in the kernel's queue: later than they came).
10. The accept thread, the one way in for a stop on a new connection, runs ACCEPT_RAISE nice
   steps above the bridge where the system lets it (as root, with CAP_SYS_NICE, or under the
   systemd unit's ``LimitNICE=-10``; elsewhere at the bridge's priority, said at debug), on
   Linux alone (there a thread has a nice of its own). A program on the host connecting from
   more threads than the port has was otherwise scheduled ahead of it thread for thread (an
   attack pass: four threads opening half-command connections; the accept thread ran 0.2 s a
   second and waited 0.5 s for a core, the kernel's queue full; raised, it ran about 0.5 s).
   What it does is bounded per connection (rule 5) and it takes no lock its clients' threads
   hold long; the stop express stays ahead of it (mqtt/express.py rule 10: EXPRESS_RAISE
   steps, more). The clients' threads it starts go back to the bridge's priority first thing:
   what they run is what clients send (rule 5's budgets), and raised they would take cores
   from the broker that carries the MQTT stops. Nothing of rule 9 depends on it.
"""

from __future__ import annotations

import errno
import functools
import ipaddress
import logging
import math
import os
import re
import selectors
import socket
import struct
import sys
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable, Sequence
from typing import Protocol, cast

from bridge.core.errors import RefusalCode, Refused
from bridge.core.haltwatch import HaltWatchers
from bridge.core.model import Command
from bridge.core.ratelimit import Budget, TokenBucket
from bridge.front import FrontRotator, HaltCounted
from bridge.interfaces.fdwait import readable

log = logging.getLogger(__name__)

USEFUL_WITHIN_S = 60.0  # bytes trickling in without a complete command: dropped after this
REFUSAL_LOG_S = 10.0  # connections turned away are logged at most this often, with a count
# rule 5: a tracker sending 20 targets and 20 readings a second spends about 3 KB/s of this
READ_BYTES = 64  # at most this much read, and so at most this many commands run, a wake-up
RATE_BYTES_S = 8192.0  # a client's budget: this many bytes a second, a burst of as many
REPLY_COST = 64  # each reply (each command answered) costs this many bytes of the budget
READ_COST = 32  # each wake-up (each read) costs this many bytes of the budget (rule 5)
MAX_UNFINISHED = 4096  # bytes without a complete command: the client is dropped
LINE_ENDS = b"\r\n"  # what ends a command, unless a front end names its own (rule 6)
LOG_S = 10.0  # rule 5's log lines, at most this often a port
ACCEPTS_S = 20.0  # rule 5: threads started a second for one peer address, at most
PENDING_GRACE_S = 2.0  # rule 3: a command half received for less is never dropped for room
SPLIT_SHARE = 0.25  # rule 3: mid-command more of its time than this: dropped first for room
SEND_STALL_S = 0.5  # rule 3: a reply still being sent after this: its client reads none
SEND_WAIT_S = 10.0  # rule 5: a client that takes no reply for this long is dropped
IDLE_S = 30.0  # rule 3: an established client that finished no command for this long is idle
ERROR_PAUSE_S = 0.05  # rule 5: accept() out of descriptors or buffers, or a bug: pause this
PARTIAL_POLL_S = 0.05  # rule 5: a waiting connection with part of a line is looked at this often
SWEEP_S = 0.01  # rule 8: waiting connections whose peer left are looked for at most this often
SEEN_KEPT = 4096  # rule 9: a connection's looks at what it has sent, at most (the oldest go)
MINE_KEPT = 64  # rule 9: the numbers of a connection's own halts kept (the oldest go: refusing)
# Windows has no MSG_DONTWAIT (the remote runs there: tests/remote/test_remote_portable.py):
# every use is a read of bytes known to wait, or a small send to a fresh connection
_DONTWAIT = getattr(socket, "MSG_DONTWAIT", 0)
_TCP_INFO: int | None = getattr(socket, "TCP_INFO", None) if sys.platform == "linux" else None
STALE = "sent before a STOP or lock ON that came first: not carried out"  # rule 9
PEERS_KEPT = 256  # rule 5: accept budgets remembered; past this, those back to full go
BACKLOG = 1024  # rule 5: the kernel's queue of connections (short: the text says why)
ACCEPT_BATCH = 256  # rule 5: connections taken from it a wake-up, at most
STOP_ACCEPTS_S = 50.0  # rule 5: connections with a stop unread let in a second, per peer
YOUNG_KEPT = 2  # rule 3: of one address's connections just come, the newest kept so many
CHATTER_S = 1.0  # rule 5: connections said connected and gone at INFO a second (a burst of
CHATTER_BURST = 10.0  # as many), the rest at DEBUG
ACCEPT_RAISE = 5  # rule 10: nice steps the accept thread runs above the bridge, where allowed


def _nice_of_this_thread() -> int | None:
    """Rule 10: the calling thread's nice; None off Linux (only there has a thread a nice of
    its own, named by its native id: elsewhere that id could name another process)."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        return os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    except OSError:
        return None


def _nice_this_thread(nice: int) -> bool:
    """Rule 10: the calling thread at ``nice`` (Linux alone), where the system lets it (root,
    CAP_SYS_NICE, or a nice limit: the systemd unit's ``LimitNICE=-10``; a lower priority,
    always); False where it keeps its own (said at debug)."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), max(-20, min(19, nice)))
        return True
    except OSError as exc:  # EACCES/EPERM: no privilege, or above the nice limit
        log.debug("the accept thread runs at the bridge's priority: %s", exc)
        return False


class RareLog:
    """One warning at most once per ``every_s``, with how many since the last said."""

    def __init__(self, every_s: float = LOG_S) -> None:
        self._every_s = every_s
        self._said_s = -math.inf
        self._since = 0
        self._lock = threading.Lock()

    def warn(self, now: float, msg: str, *args: object, exc_info: bool = False) -> None:
        with self._lock:
            self._since += 1
            if now - self._said_s < self._every_s:
                return
            count, self._since, self._said_s = self._since, 0, now
        log.warning(msg + " (%d time(s) since last said)", *args, count, exc_info=exc_info)


class Close:
    """A session's answer that ends the connection (rotctld's ``q``)."""


CLOSE = Close()


class _Client:
    """Rule 3's bookkeeping for one connected client: what ``_admit`` weighs to make room."""

    def __init__(self, thread: threading.Thread, host: str, now: float) -> None:
        self.thread = thread
        self.host = host
        self.since_s = now  # connected
        self.useful_s = now  # connected, or last finished a command
        self.pending_s: float | None = None  # first byte of a command not yet complete
        # rule 3: the first read of a run that has left a command half received at every read
        # since, and the time of the runs before it
        self.stream_s: float | None = None
        self.mid_s = 0.0
        self.done = False  # has finished a command: an established program, dropped last
        self.over_s: float | None = None  # rule 3: paused over its budget since (a flood)
        self.sending_s: float | None = None  # rule 3: a reply being sent since
        self.reading = False  # rule 3: what it sent is being read and carried out now

    def rank(self, now: float, line_unread: bool, fresh: bool = True) -> tuple[int, float]:
        """Rule 3: where this client stands in the order clients are dropped for room (the
        least first); ``line_unread``: at rest with a complete command line not read yet;
        ``fresh``: one of the YOUNG_KEPT newest connections of its address."""
        if self.over_s is not None:
            return 0, self.over_s  # a flood: paused over its budget, the longest first
        if self.sending_s is not None and now - self.sending_s > SEND_STALL_S:
            return 1, self.sending_s  # its replies not read: a send waits on it
        share = self.splitting(now)
        if share > 0.0:
            return 2, -share  # mid-command the most of its time
        if self.pending_s is not None and not self.reading:
            return 7, self.pending_s  # mid-command now: the oldest half command first
        if line_unread or self.reading:
            return 8, -self.since_s  # a line just come (a stop?), read now or in a moment
        if not self.done:  # never finished a command: the newest first, but one just come
            young = fresh and now - self.since_s <= PENDING_GRACE_S  # (its stop may come)
            return (6 if young else 3), -self.since_s
        if now - self.useful_s > IDLE_S:
            return 4, self.useful_s  # idle: the longest first
        return 5, -self.since_s  # established and busy: the newest connection first

    def splitting(self, now: float) -> float:
        """Rule 3: the share of its time connected this client has spent with a command half
        received, if that is more than PENDING_GRACE_S and more than SPLIT_SHARE; else 0."""
        mid = self.mid_s + (now - self.stream_s if self.stream_s is not None else 0.0)
        life = now - self.since_s
        return mid / life if mid > PENDING_GRACE_S and mid > SPLIT_SHARE * life else 0.0


_RANKS = (  # rule 3: why a client was dropped for room, by its ``_Client.rank``
    "sending faster than a client may",
    "reading no replies",
    "mid-command most of its time",
    "never finished a command",
    "idle",
    "the newest of the established",
    "just connected, no command yet",
    "the oldest command half received",
    "a command line not read yet",
)


def _newest_young(pool: list[tuple[socket.socket, _Client]], now: float) -> set[socket.socket]:
    """Rule 3: of each address's connections just come with no command yet, the YOUNG_KEPT
    newest (an attack pass: every such connection was kept before an established one, so ten
    silent connections a second from one program dropped Gpredict again and again, and a
    STOP it had just sent with it; the one opened for a stop is the newest when it comes)."""
    young: dict[str, list[tuple[float, socket.socket]]] = {}
    for conn, k in pool:
        if not k.done and k.pending_s is None and now - k.since_s <= PENDING_GRACE_S:
            young.setdefault(_peer_key(k.host), []).append((k.since_s, conn))
    newest = (sorted(each, key=lambda pair: pair[0])[-YOUNG_KEPT:] for each in young.values())
    return {conn for each in newest for _t, conn in each}


@functools.lru_cache(maxsize=4096)  # (asked for every waiting connection at each newcomer)
def _peer_key(host: str) -> str:
    """Rules 3 and 5: whose budget and share a connection from ``host`` counts against: every
    loopback address is one (a program on the host may bind any of 127.0.0.0/8: an attack pass
    took 500 of them, a budget each), any other address its own (an IPv6 LAN is one /64: a
    review found its hosts sharing one host's slots when counted so)."""
    return "loopback" if _loopback(host) else host


def _loopback(host: str) -> bool:
    try:
        addr = ipaddress.ip_address(host.split("%")[0])
    except ValueError:
        return False
    if isinstance(addr, ipaddress.IPv6Address) and addr.ipv4_mapped is not None:
        addr = addr.ipv4_mapped
    return addr.is_loopback


def _alive(conn: socket.socket) -> bool:
    """Rule 5: False if the peer already closed (or reset) the connection."""
    conn.setblocking(False)
    try:
        return conn.recv(1, socket.MSG_PEEK) != b""
    except BlockingIOError:
        return True
    except OSError:
        return False


_TCP_CLOSE = 7  # Linux's TCP_CLOSE, the first byte of its ``struct tcp_info`` (tcpi_state)


def _reset_by_peer(conn: socket.socket) -> bool:
    """Rule 8: whether the peer has reset the connection (TCP state CLOSE) though bytes it sent
    wait unread (a peek reads those, not the reset). Linux alone (TCP_INFO); elsewhere False."""
    if _TCP_INFO is None:
        return False
    try:
        return conn.getsockopt(socket.IPPROTO_TCP, _TCP_INFO, 1)[0] == _TCP_CLOSE
    except (OSError, IndexError):
        return False


def _arrived(conn: socket.socket, size: int) -> bytes | None:
    """Rule 5: what a connection just accepted has sent, up to ``size`` bytes, left unread (b""
    if nothing yet); None if its peer already left with nothing unread. One read where
    ``_alive``, ``_peek`` and ``_stop_in`` made one each (an attack pass: beside a flood of
    connections, every system call a newcomer costs is one the flood's connect need not)."""
    conn.setblocking(False)
    try:
        return conn.recv(size, socket.MSG_PEEK) or None
    except BlockingIOError:
        return b""
    except OSError:
        return None


def _line_ready(conn: socket.socket, ends: bytes = LINE_ENDS) -> bool:
    """Rules 3 and 5: True if a complete command (ended by one of ``ends``) waits unread in
    the kernel."""
    data = _peek(conn, MAX_UNFINISHED)
    return any(bytes([end]) in data for end in ends)


def _readable(sock: socket.socket) -> bool:
    """Whether ``sock`` is readable now (a listener: a connection waits in its queue); True
    if it cannot be said (closed meanwhile: errs toward refusing, rule 9)."""
    try:
        fd = sock.fileno()
        return fd < 0 or bool(readable((fd,), 0))
    except (OSError, ValueError):
        return True


def _peek(conn: socket.socket, size: int) -> bytes:
    """What waits unread in the kernel, up to ``size`` bytes, at once (b"" if nothing)."""
    try:
        if not _DONTWAIT:  # (Windows: a peek at bytes known to be there returns at once)
            return conn.recv(size, socket.MSG_PEEK) if readable((conn.fileno(),), 0) else b""
        if conn.gettimeout():  # a client's thread set one: recv() would poll for it first
            with socket.socket(fileno=os.dup(conn.fileno())) as peek:  # no timeout: at once
                return peek.recv(size, socket.MSG_PEEK | _DONTWAIT)
        return conn.recv(size, socket.MSG_PEEK | _DONTWAIT)
    except OSError:
        return b""


def _reset(conn: socket.socket) -> None:
    """Close with a reset: nothing of this connection lingers on our side (no TIME_WAIT)."""
    try:
        conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    except OSError:
        pass
    conn.close()


class LineSession(Protocol):
    """One client's conversation: bytes in, replies out (each reply is sent in one write)."""

    @property
    def idle(self) -> bool:
        """True when no command is half received."""
        ...

    def feed(self, data: bytes) -> Sequence[bytes | Close]: ...


try:  # rule 9 (not on Windows, where the remote runs too: tests/remote/test_remote_portable.py)
    import fcntl
    import termios

    def unread(fd: int) -> int:
        """The bytes waiting unread in the kernel on ``fd``."""
        waiting: int = struct.unpack("i", fcntl.ioctl(fd, termios.FIONREAD, b"\0" * 4))[0]
        return waiting

except ImportError:

    def unread(fd: int) -> int:
        raise OSError(errno.ENOSYS, "no FIONREAD here")


def _counted(fd: int, read: int) -> tuple[int, bool]:
    """Rule 9: the bytes ``fd``'s peer has sent so far: ``read``, and those waiting unread in
    the kernel (FIONREAD); ``read`` alone if the kernel cannot say (Windows, where the remote
    runs too: no fcntl, tests/remote/test_remote_portable.py). And whether the kernel said."""
    try:
        return read + unread(fd), True
    except OSError:
        return read, False


def halt_count(rotator: FrontRotator) -> Callable[[], int] | None:
    """Rule 9: ``rotator``'s count of every front end's halts (bridge/front.py
    ``HaltCounted.halts``: another client's of the same port among them), if it counts them;
    None if not."""
    if getattr(rotator, "halts", None) is None:
        return None
    return lambda: cast(HaltCounted, rotator).halts


def halt_watchers(rotator: FrontRotator) -> HaltWatchers | None:
    """Rule 9: those ``rotator`` tells right before it counts a halt (core/haltwatch.py), if it
    tells any."""
    watchers = getattr(rotator, "halt_watchers", None)
    return watchers if isinstance(watchers, HaltWatchers) else None


class Looks:
    """Rule 9: the looks at what one connection (or pty: ptylines.py) has sent, oldest first:
    (bytes sent, the halt count, since when) at each look; under ``lock``, as the connection's
    thread reads and as a halt is about to be counted (``LineServer._halt_coming``). Since
    when (rule 9's seen time, the monotonic clock): no byte of the entry not yet read came
    before it. ``since_s`` is that bound for the bytes no look has counted yet: a look the
    thread waited for (it found nothing unread, then its peek woke: ``waited``) moves it to
    now; a look the kernel counted at (FIONREAD) moves it to that look, after the entry is
    dated; where the kernel cannot say (Windows), only a read that took less than it asked
    for (``drained``: nothing was left) moves it. A connection's first bytes: its accept's."""

    __slots__ = ("lock", "read", "seen", "since_s")

    def __init__(self, since_s: float | None = None) -> None:
        self.lock = threading.Lock()
        self.seen: deque[tuple[int, int, float]] = deque(maxlen=SEEN_KEPT)
        self.read = 0  # the bytes its thread has read (a greeting's not counted: rule 8)
        self.since_s = time.monotonic() if since_s is None else since_s

    def look(self, fd: int, count: int, *, waited: bool = False) -> float:
        """One look (under ``lock``), at ``count`` read first: what ``fd`` has sent so far;
        ``waited``: its thread found nothing unread and its peek woke for these bytes (they
        came now, up to the time the thread took to run). Returns the look's time."""
        now = time.monotonic()
        if waited:
            self.since_s = now
        sent, counted = _counted(fd, self.read)
        self.record(sent, count, counted, now)
        return now

    def record(self, sent: int, count: int, counted: bool, now: float) -> None:
        """(under ``lock``) A look's finding: ``sent`` bytes so far, at ``count``, at ``now``;
        ``counted``: the kernel said what waits unread (the console's looks, interfaces/web/
        looks.py, count it themselves: one poll for all its connections)."""
        since = self.since_s
        seen = self.seen
        if seen and seen[-1][1] == count:  # (no halt since: one look, kept as far as it
            if seen[-1][0] > self.read:  # reaches; what it holds unread came earlier still)
                since = min(since, seen[-1][2])
            seen[-1] = sent, count, since
        else:
            seen.append((sent, count, since))
        if counted:  # (what comes after these bytes came after this look)
            self.since_s = now

    def drained(self, looked_s: float) -> None:
        """(under ``lock``) A read right after the look at ``looked_s`` took less than it asked
        for: nothing was left unread, so what comes next came after that look."""
        self.since_s = max(self.since_s, looked_s)

    def next_read(self) -> tuple[int, int, float]:
        """(under ``lock``, right after a look) How many bytes the next read may take, the
        halt count of the look that first counted them and since when they may have been
        there: no read goes past the bytes one look counted, so none holds bytes from both
        sides of a halt (the kernel cannot say what waits, Windows: as many as come, at the
        count now, since the bytes not counted may have come)."""
        seen = self.seen
        while len(seen) > 1 and seen[0][0] <= self.read:  # (looks at bytes read already)
            seen.popleft()
        sent, count, since = seen[0]
        if sent > self.read:
            return sent - self.read, count, since
        return MAX_UNFINISHED, count, min(since, self.since_s)


class Fence:
    """Rule 9: a connection's moves overtaken by a halt counted after their bytes came. The
    server tells it, before each read is fed to the session, the halt count of the first look
    at the connection that counted those bytes (``arrived``); the session's commands hand a
    move to the judge through ``move`` and carry out their own stops through ``halting``,
    whose halts are known by their numbers (``mine``: the count each made), so that another's
    halt counted while the connection's own stop is on its way is not taken for its own."""

    def __init__(self, rotator: FrontRotator) -> None:
        self.rotator = rotator
        self.count = halt_count(rotator)  # (None: a rotator that counts no halts)
        self.arrived: int | None = None  # the halt count at that look
        self.arrived_s: float | None = None  # since when those bytes may have been there
        self.mine: deque[int] = deque(maxlen=MINE_KEPT)  # the numbers of its own halts

    def overtaken(self) -> bool:
        """Whether a halt not the connection's own was counted after the bytes being fed came
        (False: none known)."""
        if self.arrived is None or self.count is None:
            return False
        arrived, now = self.arrived, self.count()
        own = sum(1 for n in self.mine if arrived < n <= now)
        return now - arrived > own

    def move(self, command: Command, described: str, since: int | None = None) -> None:
        """``command`` (a move) to the judge, unless a halt was counted after its bytes came
        (Refused, reported as the judge reports one); ``since``: the front end's own, handed
        on (the DCU-1's AM1: the count when its bearing came). The count is every front end's
        (``halts``), not the one ``since`` is in (``halts_for``: the remote's leaves out its
        own front end's), so it is judged here, right before the judge's own look."""
        if self.overtaken():
            self.rotator.report_refusal(STALE, described, origin=command.origin)
            raise Refused(RefusalCode.STALE, STALE)
        self.submit(command, described, since)

    def submit(self, command: Command, described: str, since: int | None = None) -> None:
        """``command`` to the rotator, with ``since`` and when its bytes were seen
        (``arrived_s``: front.py rule 3) where it counts halts: a stop's as a move's (the
        remote stamps both so, remote/rotator.py rule 7), read by this fence's connection (or
        pty): ``reader``, whose own halts alone lift its moves' stamps there."""
        if self.count is None and since is None:
            self.rotator.submit(command, described)
            return
        rotator = cast(HaltCounted, self.rotator)
        rotator.submit(command, described, since=since, seen_s=self.arrived_s, reader=self)

    def halting(self, halt: Callable[[], None]) -> None:
        """``halt()`` (a stop submitted), the halts it adds counted as the connection's own:
        each that the rotator's watchers are told of on this thread, numbered by the count
        before it (one counted by another thread between the two leaves a number below its
        real one: that errs toward refusing); with no watchers, every halt counted meanwhile."""
        count = self.count
        if count is None:
            halt()
            return
        watchers = halt_watchers(self.rotator)
        if watchers is None:
            before = count()
            try:
                halt()
            finally:
                self.mine.extend(range(before + 1, count() + 1))
            return
        me = threading.get_ident()
        made: list[int] = []

        def mine() -> None:
            if threading.get_ident() == me:
                made.append(count() + 1)

        watchers.add(mine)
        try:
            halt()
        finally:
            watchers.remove(mine)
        self.mine.extend(made)  # (not if it raised: a number it may not have made errs so)

    def carry(self, to: Fence) -> None:
        """A fresh session's fence on the same stream (ptylines.py): the halts this one's
        stops made stay the stream's own."""
        to.mine.extend(self.mine)


def _bind_hints(key: str) -> dict[int, str]:
    return {
        errno.EADDRINUSE: f" (another program on this port? give this rotator another {key}_port)",
        errno.EACCES: " (ports below 1024 need privileges: use 4533 or above)",
        errno.EADDRNOTAVAIL: f" ({key}_bind is not an address of this host)",
    }


class LineServer:
    """One TCP listener for one rotator; one thread per client, each with its own session.
    ``label`` names the front end in logs and errors; ``key`` is its settings prefix."""

    def __init__(
        self,
        rotator_id: str,
        port: int,
        bind: str,
        session: Callable[[], LineSession],
        *,
        label: str,
        key: str,
        max_clients: int = 16,
        max_per_peer: int | None = None,
        idle_timeout_s: float = 300.0,
        useful_within_s: float = USEFUL_WITHIN_S,
        clock: Callable[[], float] = time.monotonic,
        peer_session: Callable[[str], LineSession] | None = None,
        rate_bytes_s: float = RATE_BYTES_S,
        read_bytes: int = READ_BYTES,
        max_unfinished: int = MAX_UNFINISHED,
        ends: bytes = LINE_ENDS,
        halts: Callable[[bytes], bool] | None = None,
        singles: bytes = b"",
        greets: Callable[[bytes], bytes | None] | None = None,
        halt_count: Callable[[], int] | None = None,
        halt_watchers: HaltWatchers | None = None,
    ) -> None:
        """``peer_session``, if given, makes each client's session knowing its address (who
        sent a command: model.Origin) instead of ``session``. ``rate_bytes_s``, ``read_bytes``
        and ``max_unfinished``: rule 5; ``ends``: the bytes that end a command (rule 6);
        ``halts``: whether a client's first complete commands hold a stop (rule 5: the
        front end's parser says; none, and no connection goes ahead of the budget);
        ``singles``: bytes that are a whole command on their own and move nothing (rule 2);
        ``greets``: the answer to a waiting connection's first bytes when they are only the
        question a client asks before its command (rule 8), else None; ``halt_count``: the
        rotator's count of every front end's halts (rule 9, ``halt_count()``: its sessions'
        ``fence`` is told when their bytes came); ``halt_watchers``: the rotator's, told
        before each halt is counted (rule 9: every connection is looked at then).
        ``max_per_peer`` (rule 3): slots one address other than loopback may hold, a quarter
        of ``max_clients`` (at least 1) unless given."""
        self._rate_bytes_s = rate_bytes_s
        self._read_bytes = read_bytes
        self._max_unfinished = max_unfinished
        self._ends = ends
        # rule 5: a byte of these in a newcomer's bytes, or no command is complete there (no
        # stop: HttpGuard lets nothing through before an end but ``singles``, none of them)
        self._end_bytes = tuple(bytes([end]) for end in ends + singles)
        self._halts = halts
        self._singles = singles
        self._greets = greets  # rule 8
        self._greeted: weakref.WeakSet[socket.socket] = weakref.WeakSet()  # rule 8: once each
        self._swept_t = -math.inf  # rule 8: the last look for waiting connections whose peer left
        self._polled_t = -math.inf  # rule 5: the last look at those that sent part of a line
        self._waited_out = True  # rule 5: the accept loop's last wait ended with nothing come
        self._halt_count = halt_count  # rule 9
        # rule 9: every connection's looks at what it has sent, from its accept
        self._looks: weakref.WeakKeyDictionary[socket.socket, Looks] = weakref.WeakKeyDictionary()
        self._looks_lock = threading.Lock()
        self._halt_watchers = halt_watchers if halt_count is not None else None
        self._watcher = self._halt_coming  # (one bound method: removed as it was added)
        # rule 9: at most the count when a connection in the kernel's queue came
        self._queue_floor = 0
        self._queue_lock = threading.Lock()  # (its reading and writing, and an accept between)
        self._stop_accepts: dict[str, TokenBucket] = {}  # rule 5: per peer address
        self._http_log = RareLog()
        self._looked: weakref.WeakKeyDictionary[socket.socket, tuple[int, bool]] = (
            weakref.WeakKeyDictionary()
        )  # rule 5: a waiting connection's bytes peeked, and whether they hold a stop
        self._waiting_max = 4 * max_clients  # rule 5
        self.waiting: dict[socket.socket, tuple[str, int]] = {}  # the accept loop's, once run
        self._sel: selectors.BaseSelector | None = None  # the accept loop's, while it runs
        self._watched: set[socket.socket] = set()  # the waiting ones in ``_sel`` (``_watch``)
        self._chatter = TokenBucket.full(CHATTER_BURST, CHATTER_S, clock())  # rule 5
        self._paused_log = RareLog()
        self._dropped_log = RareLog()
        self._ended = threading.Event()  # stop(): a paused client's thread wakes at once
        self.paused = 0  # rule 5: times a client was over its budget, for the tests
        self.accept_nice: int | None = None  # rule 10: the accept thread's, once raised
        self._client_nice: int | None = None  # rule 10: its clients' threads' (the bridge's)
        self._peer_session = peer_session
        self.rotator_id = rotator_id
        self.label = label
        self._key = key
        self._session = session
        self._bind = bind
        self._requested_port = port
        self._max_clients = max_clients
        self._max_per_peer = max_per_peer if max_per_peer else max(1, max_clients // 4)
        self._accepts: dict[str, TokenBucket] = {}  # rule 5: per peer address
        self._over_log = RareLog()
        self._accept_log = RareLog()
        self._bug_log = RareLog()
        self._room_log = RareLog(REFUSAL_LOG_S)
        self._idle_timeout_s = idle_timeout_s
        self._useful_within_s = max(useful_within_s, 0.0)
        self._clock = clock
        self._refused_logged_s = -REFUSAL_LOG_S
        self._refused_since = 0
        self._listener: socket.socket | None = None
        self._wake_r, self._wake_w = -1, -1
        self._accept_thread: threading.Thread | None = None
        self._lock = threading.Lock()
        self._clients: dict[socket.socket, _Client] = {}
        self._stopping = False

    @property
    def address(self) -> tuple[str, int]:
        if self._listener is None:
            return self._bind, self._requested_port
        host, port = self._listener.getsockname()[:2]
        return host, port

    @property
    def port(self) -> int:
        return self.address[1]

    @property
    def most_held(self) -> int:
        """Rule 7: the descriptors its connections may hold at once, at most."""
        return self._max_clients + self._waiting_max + 1

    @property
    def client_count(self) -> int:
        with self._lock:
            return len(self._clients)

    def listen(self) -> None:
        """Rule 4: take the address; OSError whose strerror is one line naming the rotator, the
        address and the reason if it cannot be had. ``start`` does this too."""
        if self._listener is not None:
            return
        host, port = self._bind, self._requested_port
        try:
            family = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0][0]
            self._listener = socket.create_server(
                (host, port), family=family, backlog=BACKLOG
            )  # rule 5
        except OSError as exc:
            # create_server's strerror repeats the address; the plain reason is enough
            code = exc.errno or 0
            reason = os.strerror(code) if code > 0 else exc.strerror or str(exc)
            raise OSError(
                exc.errno,
                f"{self.label} for rotator {self.rotator_id!r}: cannot listen on {host}:{port}: "
                f"{reason}{_bind_hints(self._key).get(code, '')}",
            ) from None
        if self._halt_count is not None:  # rule 9: any connection from now came after this
            self._queue_floor = self._halt_count()

    def start(self) -> None:
        """Listen (OSError if the address cannot be had) and accept clients in a thread."""
        self.listen()
        host = self._bind
        if host not in ("127.0.0.1", "::1", "localhost"):
            log.warning(
                "%s for %s listens on %s:%d: %s has no authentication, anyone who "
                "can reach this address can turn the antenna",
                self.label,
                self.rotator_id,
                host,
                self.port,
                self.label,
            )
        self._wake_r, self._wake_w = os.pipe()
        self._stopping = False
        self._ended.clear()
        if self._halt_watchers is not None:  # rule 9
            self._halt_watchers.add(self._watcher)
            self._queue_looked(0)
        self._accept_thread = threading.Thread(
            target=self._accept_loop, name=f"{self._key}-{self.rotator_id}", daemon=True
        )
        self._accept_thread.start()
        log.info("%s for %s listening on %s:%d", self.label, self.rotator_id, *self.address)

    def stop(self, timeout_s: float = 3.0) -> None:
        """Stop listening, close every client; commands already queued stay queued."""
        if self._listener is None:
            return
        if self._accept_thread is None:  # listening, never started: nothing else to end
            self._listener.close()
            self._listener = None
            return
        with self._lock:
            self._stopping = True
            clients = list(self._clients.items())
        if self._halt_watchers is not None:
            self._halt_watchers.remove(self._watcher)
        self._ended.set()
        os.write(self._wake_w, b"x")
        self._accept_thread.join(timeout_s)
        for conn, _thread in clients:
            try:
                conn.shutdown(socket.SHUT_RDWR)  # wakes the client thread's recv()
            except OSError:
                pass
        for _conn, client in clients:
            client.thread.join(timeout_s)
        self._listener.close()
        self._listener = None
        self._accept_thread = None
        os.close(self._wake_r)
        os.close(self._wake_w)

    def _accept_loop(self) -> None:
        listener = self._listener
        assert listener is not None
        listener.setblocking(False)  # a client that gave up between select and accept
        base = _nice_of_this_thread()  # rule 10: the accept thread ahead of busy programs
        if base is not None and _nice_this_thread(base - ACCEPT_RAISE):
            self.accept_nice, self._client_nice = _nice_of_this_thread(), base
        waiting: dict[socket.socket, tuple[str, int]] = {}  # rule 5: over budget, oldest first
        self.waiting = waiting  # (read by the tests: how many wait)
        with selectors.DefaultSelector() as sel:
            self._sel, self._watched = sel, set()  # (the accept loop's alone)
            sel.register(listener, selectors.EVENT_READ)
            sel.register(self._wake_r, selectors.EVENT_READ)
            try:
                while True:  # rule 5: never a sleep while connections wait in the kernel
                    try:
                        if self._accept_once(listener, waiting, sel):
                            return
                    except Exception:  # rule 5: the port must outlive any bug in this loop
                        self._bug_log.warn(
                            self._clock(),
                            "%s for %s: accept loop error",
                            self.label,
                            self.rotator_id,
                            exc_info=True,
                        )
                        self._ended.wait(ERROR_PAUSE_S)
            finally:
                for conn in waiting:
                    conn.close()

    def _accept_once(
        self,
        listener: socket.socket,
        waiting: dict[socket.socket, tuple[str, int]],
        sel: selectors.BaseSelector,
    ) -> bool:
        """One pass of the accept loop; True when stop() asked it to end."""
        events = sel.select(self._admit_waiting(waiting, sel))
        self._waited_out = not events
        if any(key.fileobj == self._wake_r for key, _ in events):
            return True
        for key, _ in events:
            if key.fileobj is listener:  # rule 5: the queue drained, not one a wake-up
                for _ in range(ACCEPT_BATCH):
                    if not self._take(listener, waiting, sel):
                        break
                continue
            conn = key.fileobj  # a waiting one: its bytes came, or it left
            if not isinstance(conn, socket.socket) or conn not in waiting:
                continue  # reset by _take earlier in this same pass
            self._unwatch(conn)
            if not _alive(conn):
                del waiting[conn]
                self._looked.pop(conn, None)
                conn.close()
            elif self._stop_in(conn):  # a stop: ahead of the budget (_stop_now)
                self._stop_now(conn, waiting.pop(conn), waiting)
            elif not self._greet(conn, sel) and conn in self._greeted and not _peek(conn, 1):
                self._watch(conn)  # (rule 8: answered meanwhile, ``_resettable``: its command
        return False  # wakes the loop at once, a review found it left to the partial poll)

    def _stop_in(self, conn: socket.socket, data: bytes | None = None) -> bool:
        """Rule 5: whether ``conn``'s first commands (READ_BYTES of them, what its first read
        takes) hold a stop its session would carry out: what HttpGuard lets through, read by
        the front end's parser (``halts``). Asked again only when more bytes came. ``data``:
        those bytes, peeked by the caller a moment ago (else they are peeked here)."""
        if self._halts is None:
            return False
        if data is None:
            data = _peek(conn, self._read_bytes)
        if self._end_bytes and not any(end in data for end in self._end_bytes):
            return False  # no command complete (an attack pass: half a command a newcomer,
            # parsed for nothing, by the thousand)
        seen = self._looked.get(conn)
        if seen is not None and seen[0] == len(data):
            return seen[1]
        guard = HttpGuard(self._ends, self._singles)
        body = guard.feed(data)
        stop = bool(body) and guard.http is None and self._halts(body)
        self._looked[conn] = (len(data), stop)
        return stop

    def _stop_now(
        self,
        conn: socket.socket,
        peer: tuple[str, int],
        waiting: dict[socket.socket, tuple[str, int]],
    ) -> None:
        """Rule 5: a connection whose first commands hold a stop: a thread at once, within its
        peer's STOP_ACCEPTS_S a second, else it waits (no thread), ahead of the others when
        room must be made (``_queue``). Past that budget the stops come from one program
        faster than any operator sends them: the rotor is stopped by them already."""
        now = self._clock()
        if self._bucket(self._stop_accepts, _peer_key(peer[0]), STOP_ACCEPTS_S, now).take(now):
            self._let_in(conn, peer)
        else:
            self._queue(conn, peer, waiting)

    def _greet(self, conn: socket.socket, sel: selectors.BaseSelector) -> bool:
        """Rule 8: a waiting connection whose bytes are only a client's question before its
        command (``greets``) is answered, once, the bytes taken, and it waits on, woken by the
        next ones (its command: a stop goes ahead of the budget); True if it was."""
        if self._greets is None or conn in self._greeted:
            return False
        data = _peek(conn, self._read_bytes)
        answer = self._greets(data) if data else None
        if answer is None:
            return False
        self._greeted.add(conn)
        self._looked.pop(conn, None)
        try:
            looks = self._looks.get(conn)
            if looks is None:
                conn.recv(len(data), _DONTWAIT)  # (the bytes peeked, all there)
            else:  # rule 9: its thread counts from the bytes after the question
                with looks.lock:  # (a look in between would count the question's bytes)
                    conn.recv(len(data), _DONTWAIT)
                    looks.seen = deque(
                        ((max(0, sent - len(data)), count, s) for sent, count, s in looks.seen),
                        maxlen=SEEN_KEPT,
                    )
            if conn.send(answer, _DONTWAIT) != len(answer):
                return False  # (a fresh connection's buffer takes it whole: not, no answer)
        except OSError:
            return False  # (gone: the loop finds it so, or lets it in to end)
        self._watch(conn)
        return True

    def _let_in(self, conn: socket.socket, peer: tuple[str, int]) -> None:
        """Rule 5: a thread for ``conn``, out of the accept loop's books and its selector."""
        self._looked.pop(conn, None)
        self._unwatch(conn)
        conn.setblocking(True)
        self._admit(conn, peer)

    def _watch(self, conn: socket.socket) -> None:
        """Rule 5: a waiting connection woken by its next bytes (or its peer's leaving): in the
        accept loop's selector, once."""
        if self._sel is not None and conn not in self._watched:
            self._sel.register(conn, selectors.EVENT_READ)
            self._watched.add(conn)

    def _unwatch(self, conn: socket.socket) -> None:
        """Rule 5: ``conn`` out of the accept loop's selector, if it is there; before it is
        closed (its number is a new one's once closed: registered again, a KeyError in the
        loop). Asked of ``_watched``, not the selector's map, which formats a KeyError's message
        (the socket's repr, two system calls) for every connection not in it: a reset a
        newcomer, and every waiting one at every wake-up (an attack pass)."""
        if conn in self._watched:
            self._watched.discard(conn)
            if self._sel is not None:
                self._sel.unregister(conn)

    def _queue(
        self,
        conn: socket.socket,
        peer: tuple[str, int],
        waiting: dict[socket.socket, tuple[str, int]],
    ) -> None:
        """Rule 5: ``conn`` waits, no thread. Full (4 ``max_clients``): the oldest waiting that
        holds no stop is reset to make room (the newest is the operator's, come to send one:
        an attack pass found the newest reset first, a stop split across segments with it);
        if every one holds a stop: the oldest of them for a newcomer that holds one too (a
        review: the newcomer was reset, the operator's stop behind a flood of stops each with a
        move; a newer stop is the last word); the newcomer itself if its bytes hold none (a
        stop is kept before a poll: the next review); one that has sent nothing yet waits
        beyond the limit, its bytes to decide (the operator's come a moment after its
        connection), one at most: the next newcomer finds it the oldest without a stop."""
        if len(waiting) >= self._waiting_max:
            self._sweep(waiting)
        if len(waiting) >= self._waiting_max:
            # rule 8: those answered wait for their command: kept longer
            gone = next((c for c in waiting if self._resettable(c)), None)
            if gone is None:
                gone = next((c for c in waiting if not self._stop_in(c)), None)
            if gone is None and not self._stop_in(conn) and not _peek(conn, 1):
                waiting[conn] = peer  # (none sent yet: ``_accept_once`` reads its first bytes)
                return
            if gone is None:
                gone = next(iter(waiting)) if self._stop_in(conn) else conn
            waiting.pop(gone, None)
            self._looked.pop(gone, None)
            self._unwatch(gone)
            _reset(gone)
            self._over_log.warn(
                self._clock(),
                "%s for %s: %s connects faster than a client may: connection reset",
                self.label,
                self.rotator_id,
                peer[0],
            )
            if gone is conn:
                return
        waiting[conn] = peer

    def _resettable(self, conn: socket.socket) -> bool:
        """Rules 5 and 8: whether ``conn`` may be reset first to make room: not answered
        (``greets``), no stop in its bytes. One silent when last looked at is looked at again
        first: a question come since is answered (rotctl's, come a moment after its connect,
        was reset unanswered while the loop was busy with a flood, the event of its bytes not
        yet read)."""
        if conn in self._greeted or self._stop_in(conn):
            return False
        return not (
            conn in self._watched and self._sel is not None and self._greet(conn, self._sel)
        )

    def _left_without_stop(self, conn: socket.socket) -> bool:
        """Rule 8: whether ``conn``'s peer has reset it and nothing it sent holds a stop: the
        reset looked for first (its bytes are all there then: a review found a stop come
        between a peek and the look lost), then its bytes, READ_BYTES of them at most, as
        ``_stop_in`` reads them. One that sent more is kept as any (its thread reads them all:
        the same review found a client's moves, its stop after them and a reset lost; reading
        them all here, the next review found 64 KB of polls before each reset cost the loop
        50-90 ms a connection, and a flood of them kept rotctl's STOP out)."""
        if not _reset_by_peer(conn):
            return False
        if self._halts is None:
            return True
        try:
            if unread(conn.fileno()) > self._read_bytes:
                return False
        except OSError:
            return False
        return not self._stop_in(conn)  # (bytes parsed already are not again: review 132)

    def _sweep(self, waiting: dict[socket.socket, tuple[str, int]]) -> None:
        """Rule 8: the waiting connections whose peer has left and whose bytes hold no stop are
        closed (nobody waits for their answers), at most every SWEEP_S: a flood that resets its
        connections fills the waiting list with them, and the live one waiting for its
        command was reset to make room."""
        now = self._clock()
        if now - self._swept_t < SWEEP_S:
            return
        self._swept_t = now
        for conn in [
            c
            for c in waiting
            if (not _alive(c) and not self._stop_in(c)) or self._left_without_stop(c)
        ]:
            del waiting[conn]
            self._looked.pop(conn, None)
            self._unwatch(conn)
            conn.close()

    def _take(
        self,
        listener: socket.socket,
        waiting: dict[socket.socket, tuple[str, int]],
        sel: selectors.BaseSelector,
    ) -> bool:
        """Rule 5: one connection from the kernel's queue, at once: closed if its peer already
        left, a thread if its peer is within its budget (or its first commands hold a stop:
        ``_stop_now``), else it waits here (no thread); False when the queue had none (or
        accept failed)."""
        try:
            with self._queue_lock:  # rule 9: the queue found empty at this count (read first)
                count = self._halt_count() if self._halt_count is not None else 0
                try:
                    conn, peer = listener.accept()
                except BlockingIOError:  # (never lowered: a look before a halt may have
                    self._queue_floor = max(self._queue_floor, count)  # raised it already)
                    return False
                floor = self._queue_floor
        except OSError as exc:
            self._accept_log.warn(
                self._clock(), "%s for %s: accept failed: %s", self.label, self.rotator_id, exc
            )
            if exc.errno in (errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM):
                self._ended.wait(ERROR_PAUSE_S)  # the listener stays readable: no spin
            return False
        first = _arrived(conn, self._read_bytes)
        if first is None or (  # its peer already left: no thread, no budget (rule 8: reset
            first and not self._stop_in(conn, first) and self._left_without_stop(conn)
        ):  # with bytes unread, none a stop, it left too)
            self._looked.pop(conn, None)
            conn.close()
            return True
        if self._halt_count is not None:  # rule 9: looked at before each halt from now on,
            looks = Looks()  # and now: the count first, then what was sent
            with self._looks_lock:
                self._looks[conn] = looks
            count = self._halt_count()
            if self._halt_watchers is not None:  # (it came when the count was at least the
                count = min(count, floor)  # floor: no watcher looked at it in the queue)
            with looks.lock:
                looks.look(conn.fileno(), count)
        now = self._clock()
        key = _peer_key(peer[0])
        if self._stop_in(conn, first):
            self._stop_now(conn, peer, waiting)
        elif not any(_peer_key(p[0]) == key for p in waiting.values()) and self._accept_budget(
            key, now
        ).take(now):
            self._let_in(conn, peer)
        else:
            self._queue(conn, peer, waiting)
        if conn in waiting and not first:  # silent: woken by its first bytes (those that sent
            self._watch(conn)  # some: _admit_waiting looks; any come since wake it at once)
        elif conn in waiting:
            self._greet(conn, sel)
        return True

    def _halt_coming(self) -> None:
        """Rule 9: a halt is about to be counted (core/haltwatch.py): every connection, a
        waiting one's or a client's whose thread sleeps over its budget among them, is looked at
        now, at the count before it, so that what each had sent by then is not taken as sent
        after it, however late it is read."""
        assert self._halt_count is not None
        count = self._halt_count()
        with self._looks_lock:
            each = list(self._looks.items())
        for conn, looks in each:
            with looks.lock:
                if conn.fileno() >= 0:
                    looks.look(conn.fileno(), count)
        self._queue_looked(1)

    def _queue_looked(self, ahead: int) -> None:
        """Rule 9: a connection still in the kernel's queue is looked at when it is accepted,
        at the floor: the count when the queue was last found empty (by the accept loop, or
        here, before each halt: then ``ahead`` of the count, the halt about to be counted).
        Each is a bound for every connection that comes after it, so the floor only rises (a
        cold review: the loop, finding the queue empty between a halt's look and its count,
        set it back below the halt, and a target sent long after the STOP was refused)."""
        listener = self._listener
        assert self._halt_count is not None
        with self._queue_lock:
            count = self._halt_count()
            if listener is not None and not _readable(listener):
                self._queue_floor = max(self._queue_floor, count + ahead)

    def _admit_waiting(
        self, waiting: dict[socket.socket, tuple[str, int]], sel: selectors.BaseSelector
    ) -> float | None:
        """Rule 5: each waiting connection whose first commands hold a stop (``_stop_now``),
        then a thread for each whose peer is back in credit, oldest first; returns how long
        until the next may go (None: none waits). Those that sent part of a line (not in the
        selector: their bytes unread wake it at once) are read again PARTIAL_POLL_S apart, or
        when the loop's wait for that ran out, not at every wake-up (an attack pass: a flood of
        half-command connections woke the loop for each, and every one waiting was read again
        each time)."""
        now = self._clock()
        next_s: float | None = None
        held: set[str] = set()
        poll = self._waited_out or now - self._polled_t >= PARTIAL_POLL_S
        if poll:
            self._polled_t = now
        for conn, peer in list(waiting.items()):
            if conn in waiting and conn not in self._watched:  # it sent bytes: a stop now?
                if not poll:  # (the loop's wait runs out by their next look)
                    next_s = max(0.001, self._polled_t + PARTIAL_POLL_S - now)
                    continue
                if self._stop_in(conn):
                    del waiting[conn]
                    self._stop_now(conn, peer, waiting)
                elif self._greet(conn, sel):
                    continue  # (woken by its next bytes)
                if conn in waiting:
                    next_s = PARTIAL_POLL_S
        for conn, peer in list(waiting.items()):
            key = _peer_key(peer[0])
            if key in held or conn not in waiting:
                continue
            bucket = self._accept_budget(key, now)
            if not bucket.take(now):
                held.add(key)
                wait_s = max(0.001, (1.0 - bucket.tokens) / bucket.rate_per_s)
                next_s = wait_s if next_s is None else min(next_s, wait_s)
                continue
            del waiting[conn]
            self._let_in(conn, peer)
        return next_s

    def _accept_budget(self, host: str, now: float) -> TokenBucket:
        return self._bucket(self._accepts, host, ACCEPTS_S, now)

    @staticmethod
    def _bucket(
        buckets: dict[str, TokenBucket], host: str, rate_s: float, now: float
    ) -> TokenBucket:
        bucket = buckets.get(host)
        if bucket is None:
            if len(buckets) >= PEERS_KEPT:  # forget those back to a full bucket
                full = [h for h, b in buckets.items() if now - b.t >= b.burst / b.rate_per_s]
                for h in full:
                    del buckets[h]
                if len(buckets) >= PEERS_KEPT:
                    buckets.clear()
            bucket = buckets[host] = TokenBucket.full(rate_s, rate_s, now)
        return bucket

    def _make_room(self, host: str, now: float) -> tuple[bool, str]:
        """Rule 3, under the lock: whether a client from ``host`` may come in (always, but
        while the port stops), dropping the client ``_Client.rank`` puts first if the port
        (or the peer's share) is full."""
        if self._stopping:
            return False, "stopping"
        pool = list(self._clients.items())
        if not _loopback(host):
            key = _peer_key(host)
            own = [(c, k) for c, k in pool if _peer_key(k.host) == key]
            if len(own) >= self._max_per_peer:
                pool, why = own, f"{host}'s share of {self._max_per_peer} slots"
            elif len(pool) < self._max_clients:
                return True, ""
            else:
                why = f"all {self._max_clients} slots"
        elif len(pool) < self._max_clients:
            return True, ""
        else:
            why = f"all {self._max_clients} slots"
        lines = {c for c, k in pool if k.pending_s is None and _line_ready(c, self._ends)}
        fresh = _newest_young(pool, now)
        victim, rank = min(
            ((c, k.rank(now, c in lines, c in fresh)) for c, k in pool), key=lambda pair: pair[1]
        )
        gone = self._clients.pop(victim)
        try:
            victim.shutdown(socket.SHUT_RDWR)  # its thread wakes, says it is gone, closes
        except OSError:
            pass
        self._room_log.warn(
            now,
            "%s for %s: %s taken, dropped a client (%s, %s, idle %.0f s) to let one in",
            self.label,
            self.rotator_id,
            why,
            gone.host,
            _RANKS[rank[0]],
            now - gone.useful_s,
        )
        return True, ""

    def _admit(self, conn: socket.socket, peer: tuple[str, int]) -> None:
        with self._lock:
            now = self._clock()
            room, why = self._make_room(peer[0], now)
            if not room:
                _reset(conn)
                self._refused_since += 1
                if now - self._refused_logged_s >= REFUSAL_LOG_S:  # rule 3: one line, a count
                    log.warning(
                        "%s for %s: turned away %d connection(s), the last from %s:%d (%s)",
                        self.label,
                        self.rotator_id,
                        self._refused_since,
                        peer[0],
                        peer[1],
                        why,
                    )
                    self._refused_logged_s, self._refused_since = now, 0
                return
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            client = _Client(
                threading.Thread(
                    target=self._serve,
                    args=(conn, peer),
                    name=f"{self._key}-{self.rotator_id}-{peer[1]}",
                    daemon=True,
                ),
                peer[0],
                now,
            )
            self._clients[conn] = client
        client.thread.start()

    def _serve(self, conn: socket.socket, peer: tuple[str, int]) -> None:
        if self._client_nice is not None:  # rule 10: started by the raised accept thread
            _nice_this_thread(self._client_nice)
        who = f"{self.label} for {self.rotator_id}: client {peer[0]}:{peer[1]}"
        self._say("%s connected", who)
        session = self._session() if self._peer_session is None else self._peer_session(peer[0])
        with self._lock:
            me = self._clients.get(conn)  # None: already dropped to make room
        if me is None:  # rule 3: a client dropped runs nothing more, however much it sent
            conn.close()
            self._say("%s gone (dropped to make room)", who)
            return
        guard = HttpGuard(self._ends, self._singles)
        fence: Fence | None = getattr(session, "fence", None)  # rule 9
        counting = self._halt_count if fence is not None else None
        with self._looks_lock:
            looks = self._looks.get(conn) if counting is not None else self._looks.pop(conn, None)
        if looks is None or fence is None:
            looks = None
        read = 0  # rule 9: the bytes read so far
        budget = Budget(self._rate_bytes_s, self._clock())
        unfinished = 0  # rule 5: bytes since the client last finished a command
        over = False  # rule 5: over its budget now (said once each time)
        last_bytes = self._clock()
        pending_since: float | None = None  # the first byte of a command not yet complete
        stream_since: float | None = None  # rule 3: mid-command at every read since
        mid_total = 0.0  # rule 3: the time of the runs mid-command before it
        try:
            while True:
                pause_s = budget.wait_s(self._clock())
                if pause_s > 0:  # rule 5: in the kernel, unread, until back in credit
                    if not over:
                        over = True
                        me.over_s = self._clock()  # rule 3: dropped first to make room
                        self.paused += 1
                        self._paused_log.warn(
                            self._clock(), "%s sends faster than a client may: paused", who
                        )
                    if self._ended.wait(pause_s):
                        return
                    continue
                over = False
                me.over_s = None  # rule 3: what _make_room weighs
                me.pending_s, me.stream_s, me.mid_s = pending_since, stream_since, mid_total
                me.reading = False
                me.useful_s = last_bytes if pending_since is None else me.useful_s
                # rule 3: silent for the idle timeout, or a command left unfinished for a while
                now = self._clock()
                deadline = last_bytes + self._idle_timeout_s
                if pending_since is not None:
                    deadline = min(deadline, pending_since + self._useful_within_s)
                if now >= deadline:
                    idle = now >= last_bytes + self._idle_timeout_s
                    log.info("%s dropped: %s", who, "idle" if idle else "no command")
                    return
                conn.settimeout(deadline - now)
                try:
                    if looks is None:
                        data = conn.recv(self._read_bytes)
                    else:  # rule 9: nothing unread now, what comes is waited for (seen then)
                        waited = not _readable(conn)
                        if conn.recv(1, socket.MSG_PEEK):  # looked at and read in one go (a
                            with looks.lock:  # halt's look between the two miscounts)
                                assert counting is not None and fence is not None
                                looked_s = looks.look(
                                    conn.fileno(), counting(), waited=waited
                                )  # the count first, then what was sent
                                most, fence.arrived, fence.arrived_s = looks.next_read()
                                asked = min(most, self._read_bytes)
                                data = conn.recv(asked, _DONTWAIT)
                                if len(data) < asked:
                                    looks.drained(looked_s)
                                read += len(data)
                                looks.read = read
                        else:
                            data = b""
                except (TimeoutError, BlockingIOError):
                    continue
                me.reading = True  # rule 3: its lines out of the kernel, not carried out yet
                if self._clients.get(conn) is not me:  # rule 3: dropped to make room: what it
                    break  # sent is not carried out (a flood's queue ran on after its drop)
                if not data:
                    break
                last_bytes, raw = self._clock(), len(data)
                if looks is None:
                    read += raw
                data = guard.feed(data)
                if guard.http:  # (rare: a flood of them is one line at most once per LOG_S)
                    self._http_log.warn(
                        self._clock(),
                        "%s sent %s: connection closed, nothing executed "
                        "(a web page may try to reach %s on this host)",
                        who,
                        guard.http,
                        self.label,
                    )
                    return
                replies = session.feed(data) if data else ()
                conn.settimeout(SEND_WAIT_S)  # rule 5: a client that reads no reply goes
                for reply in replies:
                    if isinstance(reply, Close):
                        return
                    if reply:
                        me.sending_s = self._clock()  # rule 3: one that waits goes first
                        try:
                            conn.sendall(reply)
                        except TimeoutError:
                            log.info("%s dropped: took no reply for %g s", who, SEND_WAIT_S)
                            return
                        me.sending_s = None
                budget.spend(READ_COST + raw + REPLY_COST * len(replies), self._clock())
                finished = any(not isinstance(r, Close) for r in replies)
                if finished:
                    me.done = True  # rule 3: an established program, dropped last
                if session.idle and not guard.holding:
                    if stream_since is not None:  # rule 3: a run mid-command ends
                        mid_total += last_bytes - stream_since
                    pending_since, unfinished, stream_since = None, 0, None
                elif finished:  # rule 5: counted from the last command finished, not read
                    pending_since, unfinished = last_bytes, raw  # its tail: within this read
                else:
                    unfinished += raw
                    if pending_since is None:
                        pending_since = last_bytes
                if pending_since is not None and stream_since is None:
                    stream_since = last_bytes  # rule 3: a run of reads mid-command begins
                if unfinished > self._max_unfinished:  # rule 5: a line with no end
                    self._dropped_log.warn(
                        self._clock(),
                        "%s dropped: %d bytes and no command finished",
                        who,
                        unfinished,
                    )
                    return
        except OSError as exc:
            log.debug("%s: %s", who, exc)
        finally:
            with self._lock:
                self._clients.pop(conn, None)
            with self._looks_lock:
                self._looks.pop(conn, None)
            if looks is not None:
                with looks.lock:  # (no halt's look at a descriptor being closed)
                    conn.close()
            else:
                conn.close()
            dropped = "" if session.idle else " (an unfinished command was dropped)"
            self._say("%s gone%s", who, dropped)

    def _say(self, msg: str, *args: object) -> None:
        """Rule 5: a client's coming and going at INFO, CHATTER_S a second at most (a burst of
        CHATTER_BURST), the rest at DEBUG (an attack pass: 1,863 lines a second, and journald's
        limit then drops every line of the service, its safety warnings too)."""
        with self._lock:
            loud = self._chatter.take(self._clock())
        log.log(logging.INFO if loud else logging.DEBUG, msg, *args)


_REQUEST_LINE = re.compile(rb"^[A-Za-z]{3,10} \S* ?HTTP/\d(\.\d)?\s*$")
_REQUEST_START = re.compile(rb"[A-Za-z]{3,10} ")  # a method and its space: a request line begun
_HEADER = re.compile(rb"^[A-Za-z][A-Za-z0-9-]{1,40}:[ \t]")
HTTP_FIRST_LINE_MAX = 8192


class HttpGuard:
    """Rule 2: what a client sends is held until its first line is complete; a connection whose
    first line is an HTTP request line, or that sends a header line (``Host: ...``) at any
    point, is HTTP and nothing of it may run (a web page cross-talking to a loopback port:
    ``KHTML`` in a User-Agent would park the rotor). ``feed`` returns the bytes the parser may
    have now; ``http`` names what was seen.

    ``ends`` are the bytes that end a command (rule 6). An end other than CR or LF (a DCU-1's
    ``;``) ends the first line too, unless what came before it begins like a request line (a
    method and a space, which no such command has): then it is held to its CR or LF as an
    HTTP request line is, so ``GET /;AP1120;AM1; HTTP/1.1`` is refused whole.

    ``singles`` are bytes that are a whole command on their own and move nothing (a DCU-1's
    ``V`` and option letters: no end follows them). While everything of the first line so far
    is such bytes, they are let through at once (a DCU-1 program's ``V`` is answered when sent,
    not with its next command); the line they begin is still held and judged whole at its end,
    so a request line cut after its first byte (``O`` of ``OPTIONS``) ran that byte alone,
    which changes nothing, and is refused."""

    def __init__(self, ends: bytes = LINE_ENDS, singles: bytes = b"") -> None:
        self.http: str | None = None
        self._head: bytes | None = b""  # the first line while it is incomplete; None after
        self._line = b""  # the current line's start, for the header check
        self._other_ends = bytes(e for e in ends if e not in b"\r\n")
        self._request_like = False  # the first line began as a request line: CR or LF ends it
        self._singles = re.compile(b"[" + re.escape(singles) + b"]*") if singles else None
        self._let = 0  # bytes of the held first line let through already (singles)

    @property
    def holding(self) -> bool:
        """True while the first line is held (incomplete) beyond what was let through."""
        return self._head is not None and len(self._head) > self._let

    def feed(self, data: bytes) -> bytes:
        if self._head is not None:
            self._head += data
            # a GS-232 client ends its lines with CR alone; an HTTP request line ends in CR LF
            ended = b"\n" in data or b"\r" in data  # not in what came before: it was held
            if not ended and self._other_ends and not self._request_like:
                ended = self._ended_by_other(len(self._head) - len(data))
            if not ended and len(self._head) < HTTP_FIRST_LINE_MAX:
                return self._let_singles()
            data, self._head = self._head, None
            if _REQUEST_LINE.match(re.split(rb"[\r\n]", data, maxsplit=1)[0]):
                self.http = "an HTTP request line"
                return b""
            data = data[self._let :]
        lines = (self._line + data).split(b"\n")
        self._line = lines[-1][-64:]  # enough of a partial line to see "Name: " at its start
        for line in lines:
            if _HEADER.match(line):
                self.http = f"an HTTP header ({line.split(b':')[0].decode('ascii', 'replace')})"
                return b""
        return data

    def _let_singles(self) -> bytes:
        """What of the held first line may go now: all of it not let through yet, when the
        whole line so far is ``singles`` (the class's last paragraph); else nothing."""
        assert self._head is not None
        if self._singles is None or self._let == len(self._head):
            return b""
        if self._singles.fullmatch(self._head, self._let) is None:
            return b""
        out, self._let = self._head[self._let :], len(self._head)
        return out

    def _ended_by_other(self, new_from: int) -> bool:
        """Whether an end other than CR or LF, arrived at or after ``new_from``, ends the held
        first line (the class's last paragraph)."""
        assert self._head is not None
        cuts = [i for e in self._other_ends if (i := self._head.find(bytes([e]), new_from)) >= 0]
        if not cuts:
            return False
        if _REQUEST_START.match(self._head[: min(cuts)]):
            self._request_like = True
            return False
        return True
