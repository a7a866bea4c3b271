"""Review 48: cty.py rule 5 refuses an entity at a position no place has (a hand edit's slip,
``211.12`` for ``21.12``) "with its prefixes", and a prefix whose own ``<lat/lon>`` is no place
"alone". Skipped, their calls are looked up again by rule 3's longest prefix, and the longest
one left belongs to ANOTHER entity: a slip in Hawaii's line (``KH6``) makes every KH6 call the
United States' (``K``), listed on ``B/spots`` with ``position: "cty"`` and the mainland's
bearing, and ``R/target {"call": "KH6ABC"}`` turns the rotor there (the DX cluster's aim reads
the same book). The operator was told once, at start-up, in the log, that Hawaii was skipped;
nothing says the KH6 spots are placed in Kansas. Before 6980f791 the slip took the whole list
down (attack 12); now it silently moves a DX entity a continent away. A call of an entity the
file's reader refused has no place (listed without a bearing: book.py rule 1's "else none"),
and a prefix whose override is refused is still its own entity's (its header's place)."""

from __future__ import annotations

import json

import pytest

from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.cty import Cty, parse_csv, parse_dat
from bridge.interfaces.dxcluster.spots import Spot
from tests.dxcluster.cty_sample import CTY_CSV, CTY_DAT
from tests.integration.test_pointing_bridge import locator_centre
from tests.support.clock import FakeClock, wall_at

# Hawaii as AD1C's files give it (west-positive longitude), its latitude slipped: 211.12
HAWAII_SLIP_DAT = (
    "Hawaii:                   31:  61:  OC:   211.12:   157.48:    10.0:  KH6:\n"
    "    AH6,KH6,NH6,WH6;\n"
)
HAWAII_SLIP_CSV = "KH6,Hawaii,110,OC,31,61,211.12,157.48,10.0,AH6 KH6 NH6 WH6;\n"
# Hawaii whole, but one prefix's own position slipped (its latitude 211.12): that prefix alone
HAWAII_PREFIX_SLIP_DAT = (
    "Hawaii:                   31:  61:  OC:    21.12:   157.48:    10.0:  KH6:\n"
    "    AH6,KH6<211.12/157.48>,NH6,WH6;\n"
)


def spot(call: str) -> Spot:
    return Spot(call, 14025.0, "G4ABC", "1234", "")


def listed(cty: Cty, call: str) -> dict[str, object]:
    book = Book(cty, locator_centre("JO62QM"), clock=FakeClock(), wall=lambda: wall_at("1234"))
    assert book.add(spot(call))
    [entry] = json.loads(book.as_json())["spots"]
    return entry  # type: ignore[no-any-return]


@pytest.mark.parametrize(
    "cty",
    [parse_dat(CTY_DAT + HAWAII_SLIP_DAT), parse_csv(CTY_CSV + HAWAII_SLIP_CSV)],
    ids=["cty.dat", "cty.csv"],
)
def test_a_call_of_a_refused_entity_is_not_placed_in_another(cty: Cty) -> None:
    assert cty.refused  # (the slip is refused, as rule 5 says)
    found = cty.lookup("KH6ABC")
    assert found is None or found.name == "Hawaii", found  # never the United States
    entry = listed(cty, "KH6ABC")
    assert entry.get("entity") != "United States", entry
    assert entry.get("bearing_deg") is None, entry  # no bearing the rotor would be turned to


def test_a_prefix_whose_override_is_refused_stays_its_entitys() -> None:
    cty = parse_dat(CTY_DAT + HAWAII_PREFIX_SLIP_DAT)
    assert cty.refused
    beside = cty.lookup("NH6ABC")  # (the prefixes beside it are Hawaii's, as rule 5 says)
    assert beside is not None and beside.name == "Hawaii", beside
    found = cty.lookup("KH6ABC")
    assert found is not None and found.name == "Hawaii", found
    assert listed(cty, "KH6ABC").get("entity") == "Hawaii"
