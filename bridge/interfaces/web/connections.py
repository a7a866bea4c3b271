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
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from bridge.interfaces.web.auth import client_key

MAX_CONNECTIONS = 256
MOST_HELD = 2 * MAX_CONNECTIONS  # rule 1: a burst beyond this is closed at once (app.py rule 5)
MAX_PER_ADDRESS = 64
IDLE_S = 15.0
SWEEP_S = 1.0


@dataclass
class _Held:
    address: str
    since: float  # when it connected or last finished a request
    busy: int = 0  # requests being served
    trusted: bool = False  # a request on it showed a valid token (rule 1)


class _Refused(asyncio.Protocol):
    """Rule 1: closed as soon as it is made."""

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        transport.close()


class _Counted(asyncio.Protocol):
    """The server's own protocol for one connection, seen coming and going (rule 1)."""

    def __init__(self, keeper: Connections, inner: Any) -> None:
        self._keeper, self._inner = keeper, inner

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self._keeper.made(self, transport)
        self._inner.connection_made(transport)

    def connection_lost(self, exc: Exception | None) -> None:
        self._keeper.lost(self)
        self._inner.connection_lost(exc)

    def data_received(self, data: bytes) -> None:
        self._inner.data_received(data)

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
        self._held[transport] = _Held(address, self._clock())
        self._made[proto] = transport

    def _make_room(self, crowd: list[asyncio.BaseTransport]) -> bool:
        """Rule 1: close the oldest of ``crowd`` that has shown no token; False if none."""
        untrusted = [t for t in crowd if t in self._held and not self._held[t].trusted]
        if not untrusted:
            return False
        oldest = min(untrusted, key=lambda t: self._held[t].since)
        del self._held[oldest]
        oldest.close()
        return True

    def trust(self, transport: asyncio.BaseTransport | None) -> None:
        held = self._held.get(transport) if transport is not None else None
        if held is not None:
            held.trusted = True

    def lost(self, proto: _Counted) -> None:
        transport = self._made.pop(proto, None)
        if transport is not None:
            self._held.pop(transport, None)

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
        idle = [t for t, h in self._held.items() if h.busy == 0 and now - h.since > IDLE_S]
        for transport in idle:
            del self._held[transport]
            transport.close()
        return len(idle)

    async def sweeping(self) -> None:
        while True:
            await asyncio.sleep(SWEEP_S)
            self.sweep()
