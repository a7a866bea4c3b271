"""Attack 12: a cty file whose entity has a latitude no place has (a hand edit's slip: ``357.0``
for ``35.70``; AD1C's own files never do) loads without a word (cty.py reads any number; rule 4
skips only lines it cannot read), and once a spot of a call in that entity is kept, every
``B/spots`` made from the book raises ValueError in geo.great_circle (book.py ``_one``): the
client logs a fault and publishes no spots list at all, the good spots with it, until that spot
ages out (max_age_s, half an hour by default). Either the entity is refused at load (skipped,
counted) or its spots are listed without a bearing; the list goes on."""

from __future__ import annotations

import json

import pytest

from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.cty import parse_dat
from bridge.interfaces.dxcluster.spots import Spot
from tests.dxcluster.cty_sample import CTY_DAT
from tests.integration.test_pointing_bridge import locator_centre
from tests.support.clock import FakeClock

SLIP = "Palau:                    27:  64:  OC:   357.0:  -134.53:    -9.0:  T8:\n    T8;\n"


def spot(call: str) -> Spot:
    return Spot(call, 14025.0, "G4ABC", "1234", "")


@pytest.mark.xfail(
    strict=True,
    reason="attack 12: a cty entity at latitude 357 (a typo) takes B/spots down whenever one "
    "of its calls is spotted: as_json raises, nothing is published",
)
def test_a_cty_entity_at_no_latitude_never_takes_the_spots_list_down() -> None:
    cty = parse_dat(CTY_DAT + SLIP)
    book = Book(cty, locator_centre("JO62QM"), clock=FakeClock(), wall=lambda: 0.0)
    assert book.add(spot("JA1ABC"))
    assert book.add(spot("T88AB"))  # the entity the slip is in
    doc = json.loads(book.as_json())
    assert "JA1ABC" in [s["call"] for s in doc["spots"]]
