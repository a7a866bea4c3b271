"""Attack pass 26: a portable call whose suffix is a call area (``UA3ABC/9``: a European Russian
call on the air from Siberia, the commonest portable form in Russian spots). cty.py rule 3 drops a
lone digit as a portable suffix, so the call is placed by ``UA3``: European Russia, where the
station is not. The call area the suffix names is its place (``UA9``: Asiatic Russia; ``/2``:
Kaliningrad, a DXCC entity of its own). B/spots shows the spot 16 to 19 degrees off from Berlin,
and a turn to the call (``R/target {"call": ...}``) goes there. The real book (its cty lookup
and great circle, as B/spots carries them) on a small cty.dat written here in AD1C's format."""

from __future__ import annotations

import json

import pytest

from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.cty import parse_dat
from bridge.interfaces.dxcluster.spots import Spot
from tests.support.clock import FakeClock, wall_at

RUSSIA = (
    "European Russia:          16:  29:  EU:   53.65:  -41.37:    -4.0:  UA:\n"
    "    R,U,UA,UA1,UA3,UA4,UA6;\n"
    "Kaliningrad:              15:  29:  EU:   54.72:  -20.52:    -3.0:  UA2:\n"
    "    R2F,R2K,UA2;\n"
    "Asiatic Russia:           17:  30:  AS:   55.88:  -84.08:    -7.0:  UA9:\n"
    "    R0,R8,R9,UA0,UA8,UA9;\n"
)


@pytest.mark.parametrize(
    ("call", "entity"),
    [("UA3ABC/9", "Asiatic Russia"), ("UA3ABC/2", "Kaliningrad"), ("UA9ABC/3", "European Russia")],
)
def test_a_call_area_suffix_places_the_call_in_that_area(call: str, entity: str) -> None:
    book = Book(parse_dat(RUSSIA), (52.5, 13.4), clock=FakeClock(), wall=lambda: wall_at("1830"))
    assert book.add(Spot(call, 14025.0, "EA5WU", "1829", "cq"))
    [shown] = json.loads(book.as_json())["spots"]
    assert shown["entity"] == entity, shown
