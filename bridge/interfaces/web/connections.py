"""The console's connections: how many it holds, and for how long one may say nothing. Runs on
the console's event loop (server.py).

A socket held open without a request costs the bridge a file descriptor, and a bridge out of
descriptors cannot reconnect to its broker or reopen a serial port: anyone who can reach the
console's port could cut every interface off, STOP included. So:

Rules:
1. At most MAX_CONNECTIONS are held, and MAX_PER_ADDRESS from one address (an IPv6 address by
   its /64, as auth.py counts logins). A connection beyond either makes room by closing the
   oldest one that has not shown a token yet (``trust``): a flood of silent sockets, or of
   WebSockets that never send their token, cannot keep the operator's STOP out, since the
   STOP's connection shows its token at once and the flood's never do. Only when every held
   one has shown a token is the newcomer closed instead.
2. A connection that is not serving a request (none arrived yet, or its last one answered) is
   closed IDLE_S after that: a client that dribbles a request's head, or keeps a socket open
   and silent, holds it no longer. A request being served (an event stream, a command) is never
   cut by this; its body must arrive within BODY_S (server.py).
3. Only the event loop calls in here (the protocol factory, the server's middleware, the sweep).
4. Each connection has a budget (ratelimit.Budget) of RATE_BYTES_S bytes a second, each read
   costing READ_COST more and each request REQUEST_COST more (``turn``: a page's few requests a
   second, its loading among them, are far inside it), as the TCP ports' clients have
   (tcplines.py rule 5, docs/architecture.md "Why no front end can starve a stop"). Over it,
   the connection is paused: its socket is not read (its bytes wait in the kernel, and TCP
   holds the sender back) and a request already read waits for its turn before it is served,
   until the budget is in credit again; it is never closed for it, and its paused time is not
   idle (rule 2). Said at most once per SAY_S, with a count. The pause is the budget's own:
   aiohttp's pauses of the same socket (a queue of pipelined requests, a WebSocket's buffer)
   are kept apart (``_Gate``), so neither lifts the other's. Another connection, the
   operator's STOP among them, is served meanwhile: each budget is its own. A page's
   WebSocket reads its messages within live.py rule 7's budget besides. An attack pass: 60
   local connections pipelining ``GET api/hello`` (it needs no token) held the bridge at
   60-85 % of a core.
5. Whoever serves a request may ask to be told when its connection goes (``on_gone``): closed
   by its client (its EOF read: the socket is read whatever the request, asyncio's transport
   closes on it), reset, or closed here (rules 1 and 2). An event stream's client sends
   nothing after its request, so its handler would otherwise learn of it only when a write
   failed (live.py rule 9).
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from bridge.core.ratelimit import Budget
from bridge.interfaces.web.auth import client_key

log = logging.getLogger(__name__)

MAX_CONNECTIONS = 256
MOST_HELD = 2 * MAX_CONNECTIONS  # rule 1: a burst beyond this is closed at once (app.py rule 5)
MAX_PER_ADDRESS = 64
IDLE_S = 15.0
SWEEP_S = 1.0
RATE_BYTES_S = 16384.0  # rule 4: a connection's budget, bytes a second (a burst of as many)
REQUEST_COST = 2048  # rule 4: each request costs this many bytes of it: 8 a second
READ_COST = 64  # rule 4: each read of its socket costs this many
SAY_S = 10.0  # rule 4: a connection paused over its budget is said this often at most


class _Gate:
    """Rule 4: the transport the server is handed, whose reading is paused while the budget or
    aiohttp holds it (either), resumed when neither does; the rest is the transport's."""

    def __init__(self, transport: Any) -> None:
        self._transport = transport
        self._theirs = False  # aiohttp paused it
        self._ours = False  # over its budget (rule 4)

    def pause_reading(self) -> None:
        self._theirs = True
        self._transport.pause_reading()

    def resume_reading(self) -> None:
        self._theirs = False
        if not self._ours:
            self._transport.resume_reading()

    def hold(self) -> None:
        self._ours = True
        self._transport.pause_reading()  # (nothing, once closing: asyncio's own check)

    def release(self) -> None:
        self._ours = False
        if not self._theirs:
            self._transport.resume_reading()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._transport, name)


@dataclass
class _Held:
    address: str
    since: float  # when it connected or last finished a request
    budget: Budget  # rule 4
    gate: _Gate | None = None
    busy: int = 0  # requests being served
    trusted: bool = False  # a request on it showed a valid token (rule 1)
    paused: bool = False  # over its budget, not read (rule 4)
    waiters: list[asyncio.Future[None]] = field(default_factory=list)  # requests waiting
    gone: list[Callable[[], None]] = field(default_factory=list)  # told when it goes (rule 5)


class _Refused(asyncio.Protocol):
    """Rule 1: closed as soon as it is made."""

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        transport.close()


class _Counted(asyncio.Protocol):
    """The server's own protocol for one connection, seen coming and going (rule 1)."""

    def __init__(self, keeper: Connections, inner: Any) -> None:
        self._keeper, self._inner = keeper, inner

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        gate: Any = _Gate(transport)  # rule 4: what the server sees of it
        self._keeper.made(self, gate)
        self._inner.connection_made(gate)

    def connection_lost(self, exc: Exception | None) -> None:
        self._keeper.lost(self)
        self._inner.connection_lost(exc)

    def data_received(self, data: bytes) -> None:
        self._inner.data_received(data)
        self._keeper.spend(self, len(data) + READ_COST)  # rule 4: charged after it ran

    def eof_received(self) -> bool | None:
        result: bool | None = self._inner.eof_received()
        return result

    def pause_writing(self) -> None:
        self._inner.pause_writing()

    def resume_writing(self) -> None:
        self._inner.resume_writing()


class Connections:
    def __init__(self, factory: Callable[[], Any], clock: Callable[[], float] = time.monotonic):
        self._factory, self._clock = factory, clock
        self._held: dict[asyncio.BaseTransport, _Held] = {}
        self._made: dict[_Counted, asyncio.BaseTransport] = {}
        self._pending = 0  # made by the factory, not connected yet
        self.paused = 0  # rule 4: times a connection was paused over its budget
        self._unsaid, self._said_s = 0, -SAY_S  # rule 4: pauses not said yet, when last said

    def __len__(self) -> int:
        return len(self._held) + self._pending

    def protocol(self) -> asyncio.Protocol:
        """The protocol factory the listening socket is served with (rule 1: a burst of
        accepts beyond twice the limit is closed at once, the rest judged when connected)."""
        if len(self) >= MOST_HELD:
            return _Refused()
        self._pending += 1
        return _Counted(self, self._factory())

    def made(self, proto: _Counted, transport: asyncio.BaseTransport) -> None:
        self._pending = max(0, self._pending - 1)
        peer = transport.get_extra_info("peername")
        address = client_key(str(peer[0])) if isinstance(peer, tuple) and peer else "?"
        same = [t for t, h in self._held.items() if h.address == address]
        for crowd, limit in ((same, MAX_PER_ADDRESS), (list(self._held), MAX_CONNECTIONS - 1)):
            if len(crowd) >= limit and not self._make_room(crowd):
                transport.close()  # connection_lost follows and finds nothing held
                return
        now = self._clock()
        gate = transport if isinstance(transport, _Gate) else None
        self._held[transport] = _Held(address, now, Budget(RATE_BYTES_S, now), gate)
        self._made[proto] = transport

    def _make_room(self, crowd: list[asyncio.BaseTransport]) -> bool:
        """Rule 1: close the oldest of ``crowd`` that has shown no token; False if none."""
        untrusted = [t for t in crowd if t in self._held and not self._held[t].trusted]
        if not untrusted:
            return False
        oldest = min(untrusted, key=lambda t: self._held[t].since)
        self._drop(oldest)
        oldest.close()
        return True

    def trust(self, transport: asyncio.BaseTransport | None) -> None:
        held = self._held.get(transport) if transport is not None else None
        if held is not None:
            held.trusted = True

    def on_gone(self, transport: asyncio.BaseTransport | None, told: Callable[[], None]) -> bool:
        """Rule 5: ``told`` is called (on the event loop) when the connection goes; False, and
        ``told`` never called, when it is not held (gone already)."""
        held = self._held.get(transport) if transport is not None else None
        if held is None:
            return False
        held.gone.append(told)
        return True

    def spend(self, proto: _Counted, cost: float) -> None:
        """Rule 4: ``cost`` charged to the connection; over its budget, paused."""
        transport = self._made.get(proto)
        held = self._held.get(transport) if transport is not None else None
        if held is not None:
            self._charge(held, cost)

    async def turn(self, transport: asyncio.BaseTransport | None) -> None:
        """Rule 4: a request's turn on its connection: once the budget is in credit, charged
        REQUEST_COST (over it then: paused)."""
        if transport is None:
            return
        held = self._held.get(transport)
        if held is None:
            return
        while held.budget.wait_s(self._clock()) > 0:
            self._pause(held)
            waiter = asyncio.get_running_loop().create_future()
            held.waiters.append(waiter)
            await waiter  # (woken when it refills, or when it is closed)
            if self._held.get(transport) is not held:
                return  # (gone meanwhile)
        self._charge(held, REQUEST_COST)

    def _charge(self, held: _Held, cost: float) -> None:
        now = self._clock()
        held.budget.spend(cost, now)
        if held.budget.wait_s(now) > 0:
            self._pause(held)

    def _pause(self, held: _Held) -> None:
        if held.paused:
            return
        held.paused = True
        self.paused += 1
        if held.gate is not None:
            held.gate.hold()
        self._unsaid += 1
        now = self._clock()
        if now - self._said_s >= SAY_S:
            log.warning(
                "web console: a connection from %s sent more than its budget (%d requests a "
                "second): paused until it refills, its bytes left unread (%d time(s) since last "
                "said); the other connections are served",
                held.address,
                int(RATE_BYTES_S // REQUEST_COST),
                self._unsaid,
            )
            self._unsaid, self._said_s = 0, now
        asyncio.get_running_loop().call_later(held.budget.wait_s(now), self._refilled, held)

    def _refilled(self, held: _Held) -> None:
        """Rule 4: its pause over, once in credit (a paused connection is not idle: rule 2)."""
        if not held.paused:
            return
        now = self._clock()
        wait_s = held.budget.wait_s(now)
        if wait_s > 0:
            asyncio.get_running_loop().call_later(wait_s, self._refilled, held)
            return
        held.paused = False
        held.since = now
        if held.gate is not None:
            held.gate.release()
        self._wake(held)

    def _wake(self, held: _Held) -> None:
        waiters, held.waiters = held.waiters, []
        for waiter in waiters:
            if not waiter.done():
                waiter.set_result(None)

    def lost(self, proto: _Counted) -> None:
        transport = self._made.pop(proto, None)
        if transport is not None:
            self._drop(transport)

    def _drop(self, transport: asyncio.BaseTransport) -> None:
        """No longer held: any request waiting for its turn (rule 4) let go."""
        held = self._held.pop(transport, None)
        if held is not None:
            held.paused = False
            self._wake(held)
            gone, held.gone = held.gone, []
            for told in gone:  # rule 5
                told()

    def started(self, transport: asyncio.BaseTransport | None) -> None:
        held = self._held.get(transport) if transport is not None else None
        if held is not None:
            held.busy += 1

    def finished(self, transport: asyncio.BaseTransport | None) -> None:
        held = self._held.get(transport) if transport is not None else None
        if held is not None:
            held.busy = max(0, held.busy - 1)
            held.since = self._clock()

    def sweep(self) -> int:
        """Rule 2: close what has been idle too long; how many were closed."""
        now = self._clock()
        self._pending = 0  # every protocol made before this sweep has connected (or failed)
        idle = [
            t
            for t, h in self._held.items()
            if h.busy == 0 and not h.paused and now - h.since > IDLE_S
        ]
        for transport in idle:
            self._drop(transport)
            transport.close()
        return len(idle)

    async def sweeping(self) -> None:
        while True:
            await asyncio.sleep(SWEEP_S)
            self.sweep()
