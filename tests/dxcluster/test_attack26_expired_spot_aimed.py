"""Attack pass 26: a call target (``R/target {"call": ...}``) takes "the newest kept spot of the
call" (client.py rule 4), and no spot is kept older than ``max_age_s`` (book.py rule 2). But the
aim thread reads the book as the client's thread last pruned it, and while the node is down the
client prunes only after each attempt to connect: a back-off of up to MAX_BACKOFF_S (60 s) apart.
A spot past its age inside that window still places the call: here K1ABC, spotted
from Hawaii (``BL11`` in the comment), 30 min 25 s ago by its own time, is turned to (351 degrees
from Berlin) where the call alone (the cty file: the United States) is 305 degrees. The
client's aim thread and book are the real ones, in virtual time (the book's monotonic clock);
the rotator is a recording one (test_client.py's ``Asked``)."""

from __future__ import annotations

from bridge.core.model import Origin, Source
from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.client import MAX_BACKOFF_S, DxCluster
from bridge.interfaces.dxcluster.cty import parse_dat
from bridge.interfaces.dxcluster.spots import Spot
from tests.dxcluster.cty_sample import CTY_DAT
from tests.dxcluster.test_client import Asked
from tests.support.clock import FakeClock, wall_at

MAX_AGE_S = 1800.0


def test_a_call_target_never_turns_to_a_spot_past_its_age() -> None:
    clock = FakeClock(1000.0)
    wall = [wall_at("1830")]
    book = Book(
        parse_dat(CTY_DAT), (52.5, 13.4), max_age_s=MAX_AGE_S, clock=clock, wall=lambda: wall[0]
    )
    assert book.add(Spot("K1ABC", 14025.0, "EA5WU", "1830", "KH6 portable BL11"))
    published: list[str] = []
    dx = DxCluster("127.0.0.1", 9, "G4ABC", book, published.append, clock=clock)
    # the node went down; the client's last attempt to connect pruned the book (its tick)
    # a few seconds before the spot's age ran out, then waits its back-off
    clock.t += MAX_AGE_S - 5.0
    wall[0] += MAX_AGE_S - 5.0
    dx._tick()
    assert book.newest("K1ABC") is not None  # still young enough: rightly kept
    # half a back-off later (no tick in between), the spot is 30 min 25 s old by its own time
    clock.t += MAX_BACKOFF_S / 2
    wall[0] += MAX_BACKOFF_S / 2
    rot, who = Asked(), Origin(Source.MQTT, "G4ABC")
    dx.aim(rot, "K1ABC", False, "target K1ABC", who)  # type: ignore[arg-type]
    dx._turn(dx._aims.get_nowait())  # type: ignore[arg-type]
    # what the call alone says (the cty file: the United States), not Hawaii's old spot
    assert rot.calls == [("go", 37.53, -91.67, Source.DXCLUSTER, "target K1ABC", False, who)]
