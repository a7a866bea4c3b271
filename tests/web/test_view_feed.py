"""The console's map data (interfaces/web/view.py) and its live feed (interfaces/web/feed.py),
without a server."""

from __future__ import annotations

import asyncio
import json
import math

from bridge.core.model import ErrorEvent, ErrorKind, MotionState, RotatorStatus
from bridge.interfaces.web.feed import EVENTS_KEPT, Feed, Shape, sse, websocket
from bridge.interfaces.web.view import SCALE, land_doc, land_rings

BERLIN = (52.5, 13.4)


def _points(ring: list[int]) -> list[tuple[float, float]]:
    return [(ring[i] / SCALE, ring[i + 1] / SCALE) for i in range(0, len(ring), 2)]


def test_the_land_lies_on_the_disc_without_jumps_across_it() -> None:
    doc = land_doc(BERLIN, land_rings())
    assert doc["scale"] == SCALE
    rings, closed = doc["rings"], doc["closed"]
    assert isinstance(rings, list) and isinstance(closed, list) and len(rings) == len(closed)
    for ring in rings:
        points = _points(ring)
        assert all(math.hypot(x, y) <= 1.0005 for x, y in points)
        assert all(math.dist(a, b) <= 0.25 for a, b in zip(points, points[1:], strict=False))


def test_the_station_s_own_land_is_at_the_centre_and_the_antipode_on_the_rim() -> None:
    doc = land_doc(BERLIN, land_rings())
    nearest = min(math.hypot(x, y) for ring in doc["rings"] for x, y in _points(ring))
    assert nearest < 0.02  # Berlin is on land: some coast within ~400 km of the centre
    # seen from the middle of the Pacific (antipode: Botswana), Africa wraps round the rim and
    # is split there rather than drawn across the disc
    pacific = land_doc((-21.0, -155.0), land_rings())
    assert not all(pacific["closed"])


def _status(bearing: float) -> RotatorStatus:
    return RotatorStatus("hf", MotionState.MOVING, bearing, connected=True, available=True)


def test_a_page_gets_the_newest_status_of_each_rotator_and_every_event_kept() -> None:
    async def run() -> None:
        feed = Feed({"hf": Shape(False, False), "vhf": Shape(True, False)})
        feed.status("hf", _status(10.0), 1.0)
        page = feed.join()
        assert page.wake.is_set()  # joined: the newest first
        first = [sse(m) for m in page.take()]
        assert len(first) == 1 and '"bearing":10' in first[0] and first[0].startswith("event: ")
        for b in range(20, 100, 10):  # a slow page: only the newest is owed
            feed.status("hf", _status(float(b)), 2.0)
        feed.status("vhf", _status(5.0), 2.0)
        for i in range(EVENTS_KEPT + 5):
            feed.event("hf", ErrorEvent(ErrorKind.REFUSED, f"no {i}", "target 1", 3.0))
        taken = list(page.take())
        chunks = [sse(m) for m in taken]
        assert json.loads(websocket(taken[0]))["data"]["status"]["bearing"] == 90
        statuses = [c for c in chunks if c.startswith("event: status")]
        errors = [c for c in chunks if c.startswith("event: error")]
        assert len(statuses) == 2 and '"bearing":90' in statuses[0]
        data = json.loads(statuses[1].split("data: ", 1)[1])
        assert data["rotator"] == "vhf" and "elevation" in data["status"]
        assert len(errors) == EVENTS_KEPT and '"no 24"' in errors[-1]
        assert not page.wake.is_set() and list(page.take()) == []
        feed.close()
        assert page.closed and page.wake.is_set()

    asyncio.run(run())


def test_a_page_gets_the_newest_spot_list_after_the_statuses_and_one_joining_gets_it() -> None:
    async def run() -> None:
        feed = Feed({"hf": Shape(False, False)})
        page = feed.join()
        assert list(page.take()) == []  # nothing yet: no spots message either
        feed.status("hf", _status(10.0), 1.0)
        for call in ("JA1ABC", "W1XYZ", "VK2XYZ"):  # a slow page: only the newest list
            feed.spots(json.dumps({"spots": [{"call": call}]}))
        taken = [json.loads(websocket(m)) for m in page.take()]
        assert [m["event"] for m in taken] == ["status", "spots"]
        assert taken[1]["data"] == {"spots": [{"call": "VK2XYZ"}]}
        later = feed.join()
        names = [name for name, _ in later.take()]
        assert names == ["status", "spots"]

    asyncio.run(run())
