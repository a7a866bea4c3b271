"""Attack 13: a spot the node replays when the client logs in again. Many nodes send the last
spots they had to every login (CC Cluster, AR-Cluster's login spots), so each reconnect of the
client brings spots it has already read, older than the ones it read since. The book keeps
"the newest spot of a call" by the order the lines came (book.py rule 2), so the replayed,
older spot of a call took the place of the newer one: B/spots showed the call where it was
spotted before, and ``R/target {"call": ...}`` turned the rotor there (22 degrees off). Fixed:
the book keeps the newer spot of a call by the spot's own time (book.py rule 2).

Real parts: the client's telnet session against the fake node on loopback (two logins: the
line dropped in between), its book and its aim thread, a recording rotator."""

from __future__ import annotations

import json
from collections.abc import Iterator

import pytest

from bridge.core import geo
from bridge.core.model import Origin, Source
from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.client import DxCluster
from bridge.interfaces.dxcluster.cty import parse_dat
from tests.dxcluster.cty_sample import CTY_DAT
from tests.dxcluster.test_client import Asked
from tests.support import wait_until
from tests.support.clock import RunningWall
from tests.support.cluster import FakeCluster, Session
from tests.support.waiting import slow

# W6XYZ in California, as a skimmer placed it (CM87) at 18:35; at 18:29 it was spotted with no
# locator (the United States' centre in the cty file, some 30 degrees of longitude east)
NEWER = b"DX de EA5WU:     14025.0  W6XYZ        FT8 -12 dB CM87               1835Z\r\n"
OLDER = b"DX de DL1ABC:    14025.0  W6XYZ        cq up 2                       1829Z\r\n"
LIVE = b"DX de G4ABC:     14030.0  JA1ABC       cq                            1836Z\r\n"


@pytest.fixture
def published() -> Iterator[list[str]]:
    yield []


def spot_of(published: list[str], call: str) -> dict[str, object] | None:
    if not published:
        return None
    spots = json.loads(published[-1])["spots"]
    return next((s for s in spots if s["call"] == call), None)


def test_a_spot_replayed_at_a_new_login_does_not_replace_the_newer_one(
    published: list[str],
) -> None:
    def first(s: Session) -> None:  # the 18:29 spot, then the 18:35 one; the line drops
        s.send(b"login: ")
        cluster.logins.append(s.read_line())
        s.send(OLDER + NEWER)

    def again(s: Session) -> None:  # the login's replay of an older spot, then a live one
        s.send(b"login: ")
        cluster.logins.append(s.read_line())
        s.send(OLDER + LIVE)
        cluster.done.wait(slow(30))

    cluster = FakeCluster([first, again])
    book = Book(parse_dat(CTY_DAT), (52.5, 13.4), wall=RunningWall("1837"))  # (LIVE: 1836Z)
    dx = DxCluster("127.0.0.1", cluster.port, "G4ABC", book, published.append, backoff_s=0.01)
    dx.start()
    try:
        wait_until(lambda: spot_of(published, "JA1ABC") is not None, 20, "the live spot")
        assert cluster.logins == [b"G4ABC", b"G4ABC"]
        rot, who = Asked(), Origin(Source.MQTT, "G4ABC")
        dx.aim(rot, "W6XYZ", False, "target W6XYZ", who)  # type: ignore[arg-type]
        wait_until(lambda: len(rot.calls) == 1, 10, "the call turned to")
    finally:
        dx.stop()
        cluster.close()
    shown = spot_of(published, "W6XYZ")
    assert shown is not None
    assert shown.get("locator") == "CM87", shown  # the dashboard: where it was spotted last
    lat, lon = geo.parse_locator("CM87")
    assert rot.calls[0][:3] == ("go", lat, lon), rot.calls  # the rotor: the same place
    assert not cluster.errors, cluster.errors
