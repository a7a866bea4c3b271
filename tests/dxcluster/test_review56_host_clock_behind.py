"""Review 56: a host clock a few minutes behind the node's (or a node's clock a few minutes
ahead: DX clusters' clocks drift, a Pi's before NTP) keeps no spot at all.

docs/dxcluster.md and book.py rule 2 say a host clock wrong by more than ``max_age_min``
keeps no spot. But spot_time reads a time more than SKEW_S (5 minutes) ahead of the host's
clock as yesterday's, so with the host 6 minutes behind the node, every fresh spot the node
sends is 23h54 old and not taken, whatever ``max_age_min`` (30 here): B/spots, the console's
map, Home Assistant's select and R/target {"call": ...} are empty, and the log blames a
replay or the host clock being wrong by more than ``max_age_min``. Before 5386e3f3 a spot's
age was by when it was heard, so such a host kept them.
"""

from __future__ import annotations

from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.spots import Spot
from tests.support.clock import FakeClock, wall_at


def test_a_host_clock_six_minutes_behind_the_node_still_keeps_fresh_spots() -> None:
    clock = FakeClock(0.0)
    # the node's clock says 12:40 when the host's says 12:34 (wrong by 6 min < max_age 30 min)
    b = Book(None, None, max_age_s=1800.0, clock=clock, wall=lambda: wall_at("1234") + clock.t)
    kept = [b.add(Spot(call, 14025.0, "EA5WU", "1240", "")) for call in ("JA1ABC", "VK2XYZ")]
    assert kept == [True, True]
    assert set(b.calls()) == {"JA1ABC", "VK2XYZ"}
    assert b.too_old == 0
