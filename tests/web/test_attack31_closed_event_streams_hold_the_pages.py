"""Attack 31 (resources under churn): an event stream its client closed keeps its place among
MAX_PAGES until the next ping, and the operator's page is refused 503 meanwhile.

``api/events`` (live.py ``events``) leaves the feed only when a write to the client fails:
the handler sleeps on the page's wake-up, and nothing reads the connection, so a client that
closed is noticed at the next status or ping (PING_S, 10 s), not when it goes. A script that
opens and closes the stream (a poll with ``curl --max-time``, a flow reconnecting over a
flaky link, anyone holding a token) MAX_PAGES times in PING_S fills every place with streams
nobody reads, and every page is refused (503): the operator's console, its live feed and
the STOP its WebSocket carries (rule 5), for as long as that goes on. A WebSocket's close is
seen at once (its reader, ``_read``); a stream's is not.

Real parts: the bridge in this process on an emulated Rotor-EZ (pty), a real mosquitto, the
console over real HTTP; MAX_PAGES made 5 so that a handful of streams fill it (as the other
page-limit tests do).
"""

from __future__ import annotations

import aiohttp
import pytest

from bridge.interfaces.web import live
from tests.support.console import ConsoleClient, EventStream, run_async
from tests.support.rig import Rig
from tests.web.test_attack2_console import _page, console  # noqa: F401  (the fixture)

PLACES = 5
TRIES = 2  # (a ping tick between the closes and the page would hide it once, not twice)


def _streams_opened_and_closed(client: ConsoleClient, n: int) -> int:
    """Up to ``n`` event streams, each served (its first event read), then closed by the
    client; how many were served (a refused one, 503, ends it)."""
    for served in range(n):
        try:
            stream = EventStream(client)
        except AssertionError:  # (refused: every place is held)
            return served
        stream.next()
        stream.close()
    return n


def _operators_page(client: ConsoleClient) -> object:
    """The console page's own WebSocket (its token with the opening request): "served" once it
    said hello, else the HTTP status it was refused with."""
    url = f"http://127.0.0.1:{client.port}/api/live"

    async def opened() -> object:
        async with aiohttp.ClientSession() as session:
            ws = await _page(session, url, client)
            if not isinstance(ws, aiohttp.ClientWebSocketResponse):
                return ws  # (the status it was refused with, or what came instead of hello)
            await ws.close()
            return "served"

    return run_async(opened())


def test_event_streams_their_clients_closed_leave_room_for_the_operators_page(
    console: tuple[Rig, ConsoleClient],  # noqa: F811  (the fixture)
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _rig, client = console
    monkeypatch.setattr(live, "MAX_PAGES", PLACES)
    seen = []
    for _ in range(TRIES):
        served = _streams_opened_and_closed(client, PLACES)
        seen.append((served, _operators_page(client)))
    assert seen == [(PLACES, "served")] * TRIES, (
        f"(event streams served and closed, then the operator's page) each time: {seen}"
    )
