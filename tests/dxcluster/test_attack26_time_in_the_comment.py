"""Attack pass 26: a spot whose comment ends with a time (``QRV til 2300Z``, ``QSX 1835Z``) right
before the spot's own. spots.py reads the time from the end: the last word, or the word before
it "(then the last is a locator)"; the earlier of the two when both could be. But the last word
is taken for a locator without looking at it: ``1829Z`` is no locator (``[A-R]{2}[0-9]{2}``),
and the comment's ``2300Z`` becomes the spot's time. Heard at 18:30, a spot "of 23:00" is
yesterday's (book.py rule 2), 19.5 hours old: not taken. The dashboard never lists the DX that
is on the air now, and a turn to its call goes to the cty entity, not the locator its spotter
gave. The client's telnet session against the fake node on loopback, its real book."""

from __future__ import annotations

import json

from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.client import DxCluster
from bridge.interfaces.dxcluster.cty import parse_dat
from tests.dxcluster.cty_sample import CTY_DAT
from tests.support import wait_until
from tests.support.clock import RunningWall
from tests.support.cluster import FakeCluster, Session
from tests.support.waiting import slow

# spotted at 18:29 with its locator, the operator saying they are on until 23:00
SPOT = b"DX de EA5WU:     14025.0  JA1ABC       PM95 QRV til 2300Z            1829Z\r\n"
LIVE = b"DX de G4ABC:     14030.0  W1XYZ        cq                            1829Z\r\n"


def calls(published: list[str]) -> list[str]:
    if not published:
        return []
    return [s["call"] for s in json.loads(published[-1])["spots"]]


def test_a_time_at_the_end_of_the_comment_is_not_the_spots_time() -> None:
    published: list[str] = []

    def node(s: Session) -> None:
        s.send(b"login: ")
        cluster.logins.append(s.read_line())
        s.send(SPOT + LIVE)
        cluster.done.wait(slow(30))

    cluster = FakeCluster([node])
    book = Book(parse_dat(CTY_DAT), (52.5, 13.4), wall=RunningWall("1830"))
    dx = DxCluster("127.0.0.1", cluster.port, "G4ABC", book, published.append, backoff_s=0.01)
    dx.start()
    try:
        wait_until(lambda: "W1XYZ" in calls(published), 20, "the spot after it listed")
    finally:
        dx.stop()
        cluster.close()
    spots = {s["call"]: s for s in json.loads(published[-1])["spots"]}
    assert "JA1ABC" in spots, spots  # the DX on the air now, on the dashboard
    assert spots["JA1ABC"]["time"] == "1829Z"
    assert spots["JA1ABC"]["locator"] == "PM95"
    assert not cluster.errors, cluster.errors
