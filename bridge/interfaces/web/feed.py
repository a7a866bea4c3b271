"""The console's live feed: the newest status of each rotator and the error events, to every open
page. Runs on the console's event loop; the serial-lines thread only queues into it.

Rules:
1. ``status`` and ``event`` are called on the event loop (live.py hands them over with
   ``call_soon_threadsafe``: the lines thread never waits for a page, docs/architecture.md rule 3).
2. A status is rendered once, as the R/status document (interfaces/mqtt/payloads.py), whatever the
   number of pages (and not at all while none is open: live.py keeps the newest for the next to
   join); each page then gets the newest per rotator. A page that reads slowly skips statuses in
   between, never falls behind: what waits for it is one status per rotator and the last
   EVENTS_KEPT events, whatever it costs the others.
3. A page that joins gets the newest status of every rotator first, then changes.
4. ``close`` ends every page's stream (the bridge is stopping): the page sees the bridge go.
5. ``tick`` owes every page a sign of life and ends the streams whose token has run out.
6. ``spots`` is the DX cluster's list (``B/spots``' document, interfaces/dxcluster/book.py) as it
   is: one newest kept, a page owed at most the newest (after the statuses), a page that joins gets
   it.
"""

from __future__ import annotations

import asyncio
import json
import math
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field

from bridge.core.model import ErrorEvent, RotatorStatus
from bridge.interfaces.mqtt.payloads import StatusText

EVENTS_KEPT = 20
Message = tuple[str, str]  # (event name, its JSON), written out per transport (sse, websocket)


@dataclass(frozen=True)
class Shape:
    """How a rotator's R/status document is rendered (payloads.StatusText's switches)."""

    has_elevation: bool
    shows_raw: bool


@dataclass(eq=False)  # a set of pages: each is itself, not its contents
class Page:
    """One open event stream."""

    statuses: dict[str, Message] = field(default_factory=dict)  # rotator -> not yet sent
    spots: Message | None = None  # the newest spot list not yet sent (rule 6)
    events: deque[Message] = field(default_factory=lambda: deque(maxlen=EVENTS_KEPT))
    wake: asyncio.Event = field(default_factory=asyncio.Event)
    closed: bool = False  # the page went, or the bridge is stopping
    expires: float = math.inf  # its token's end (wall clock): the stream ends then
    expired: bool = False
    ping: bool = False  # owed a sign of life (``tick``)

    def take(self) -> Iterator[Message]:
        """What is owed, statuses first (rule 2), and nothing owed after."""
        self.wake.clear()
        statuses, self.statuses = self.statuses, {}
        yield from statuses.values()
        spots, self.spots = self.spots, None
        if spots is not None:
            yield spots
        while self.events:
            yield self.events.popleft()


class Feed:
    def __init__(self, shapes: dict[str, Shape]) -> None:
        self._shapes = shapes
        self._texts: dict[str, StatusText] = {}  # rotator -> its R/status, made (rule 2)
        self._newest: dict[str, Message] = {}
        self.newest_spots: str | None = None  # rule 6: B/spots' document
        self.rendered: dict[str, float] = {}  # rotator -> the time of the status rendered last
        self._pages: set[Page] = set()
        self.closed = False

    @property
    def pages(self) -> int:
        return len(self._pages)

    def join(self) -> Page:
        page = Page(statuses=dict(self._newest))  # rules 3, 6
        if self.newest_spots is not None:
            page.spots = ("spots", self.newest_spots)
        page.wake.set()
        if self.closed:
            page.closed = True
        self._pages.add(page)
        return page

    def tick(self, now_wall: float) -> None:
        """Every PING_S (live.py): each page is owed a sign of life, and one whose token has
        run out is ended (rule 5). One timer for all pages, not one per page and wake."""
        for page in self._pages:
            page.expired = page.expired or now_wall >= page.expires
            page.ping = True
            page.wake.set()

    def leave(self, page: Page) -> None:
        self._pages.discard(page)

    def status(self, rotator_id: str, status: RotatorStatus, t_wall: float) -> None:
        shape = self._shapes[rotator_id]
        text = self._texts.get(rotator_id)
        if text is None:
            text = self._texts[rotator_id] = StatusText(shape.has_elevation)
        doc = text.render(status, t_wall, shape.shows_raw)
        head = f'{{"rotator":{json.dumps(rotator_id)},"t":{t_wall:.4f},"status":'
        chunk = ("status", f"{head}{doc}}}")
        self._newest[rotator_id] = chunk
        self.rendered[rotator_id] = t_wall
        for page in self._pages:
            page.statuses[rotator_id] = chunk
            page.wake.set()

    def spots(self, doc: str) -> None:
        """Rule 6."""
        self.newest_spots = doc
        for page in self._pages:
            page.spots = ("spots", doc)
            page.wake.set()

    def event(self, rotator_id: str, event: ErrorEvent) -> None:
        doc = {"rotator": rotator_id, **event.as_dict()}
        chunk = ("error", json.dumps(doc, separators=(",", ":")))
        for page in self._pages:
            page.events.append(chunk)
            page.wake.set()

    def close(self) -> None:
        """Rule 4."""
        self.closed = True
        for page in self._pages:
            page.closed = True
            page.wake.set()


def sse(message: Message) -> str:
    """``message`` on an event stream (``api/events``)."""
    name, data = message
    return f"event: {name}\ndata: {data}\n\n"


def websocket(message: Message) -> str:
    """``message`` on the page's WebSocket (``api/live``): one JSON text each."""
    name, data = message
    return f'{{"event":"{name}","data":{data}}}'
