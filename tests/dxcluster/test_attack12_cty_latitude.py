"""Attack 12: a cty file whose entity has a latitude no place has (a hand edit's slip: ``357.0``
for ``35.70``; AD1C's own files never do) loads without a word (cty.py reads any number; rule 4
skips only lines it cannot read), and once a spot of a call in that entity is kept, every
``B/spots`` made from the book raises ValueError in geo.great_circle (book.py ``_one``): the
client logs a fault and publishes no spots list at all, the good spots with it, until that spot
ages out (max_age_s, half an hour by default). Either the entity is refused at load (skipped,
counted) or its spots are listed without a bearing; the list goes on."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pytest

from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.cty import Cty, Entity, parse_csv, parse_dat
from bridge.interfaces.dxcluster.setup import dxcluster
from bridge.interfaces.dxcluster.spots import Spot
from bridge.settings.dxcluster import DxClusterSettings
from tests.dxcluster.cty_sample import CTY_CSV, CTY_DAT
from tests.integration.test_pointing_bridge import locator_centre
from tests.support.clock import FakeClock, wall_at

SLIP = "Palau:                    27:  64:  OC:   357.0:  -134.53:    -9.0:  T8:\n    T8;\n"


def spot(call: str) -> Spot:
    return Spot(call, 14025.0, "G4ABC", "1234", "")


def test_a_cty_entity_at_no_latitude_never_takes_the_spots_list_down() -> None:
    cty = parse_dat(CTY_DAT + SLIP)
    book = Book(cty, locator_centre("JO62QM"), clock=FakeClock(), wall=lambda: wall_at("1234"))
    assert book.add(spot("JA1ABC"))
    assert book.add(spot("T88AB"))  # the entity the slip is in
    doc = json.loads(book.as_json())
    assert "JA1ABC" in [s["call"] for s in doc["spots"]]


def test_the_entity_is_refused_where_it_is_read_and_said_naming_its_line() -> None:
    """cty.py rule 5: the header refused, its calls placed nowhere (review 48), the one reason
    kept for the log; the same in cty.csv, and for a prefix's own <lat/lon> (that prefix alone,
    at its entity's place)."""
    cty = parse_dat(CTY_DAT + SLIP)
    assert cty.lookup("T88AB") is None and cty.lookup("JA1ABC") is not None
    assert cty.refused == [
        "line 12: 'Palau': latitude '357.0' is no place's (-90..90); its calls are placed nowhere"
    ]
    csv = parse_csv(CTY_CSV + "T8,Palau,22,OC,27,64,7.45,-534.53,-9.0,T8;\n")
    assert csv.lookup("T88AB") is None and csv.lookup("VK2ABC") is not None
    assert csv.refused == [
        "line 6: 'Palau': longitude '-534.53' is no place's (-180..180); its calls are placed "
        "nowhere"
    ]
    odd = parse_dat(CTY_DAT.replace("<27.10/-142.20>", "<127.10/-142.20>"))
    japan = odd.lookup("JA1ABC")
    assert japan is not None and odd.lookup("JA1XYZ/JD1") == japan  # (Japan's own place)
    assert len(odd.refused) == 1 and odd.refused[0].startswith(
        "line 3: '=JA1XYZ/JD1<127.10/-142.20>' of 'Japan': latitude '127.10' is no place's"
    )


def test_the_refusal_is_logged_once_at_start(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    (tmp_path / "cty.dat").write_text(CTY_DAT + SLIP)
    settings = DxClusterSettings(
        enabled=True, host="dx.example", login="N0CALL", cty_file=tmp_path / "cty.dat"
    )
    with caplog.at_level(logging.WARNING):
        dxcluster(settings, None, lambda payload: None)
    said = [r.getMessage() for r in caplog.records if "Palau" in r.getMessage()]
    assert len(said) == 1 and "cty.dat line 12: 'Palau': latitude '357.0'" in said[0], said


def test_one_spot_whose_entry_cannot_be_made_is_left_out_and_the_rest_listed(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """book.py rule 5: a place no cty file read now gives (a Cty made by hand) is left out of
    B/spots, said once while it is kept; the list is made of the rest."""
    nowhere = Entity("Palau", "OC", 27, 64, 357.0, 134.53, "T8")
    cty = parse_dat(CTY_DAT)
    cty = Cty({**cty.prefixes, "T8": nowhere}, cty.exact)
    book = Book(cty, locator_centre("JO62QM"), clock=FakeClock(), wall=lambda: wall_at("1234"))
    assert book.add(spot("T88AB")) and book.add(spot("JA1ABC"))
    with caplog.at_level(logging.WARNING):
        first, second = json.loads(book.as_json()), json.loads(book.as_json())
    assert [s["call"] for s in first["spots"]] == ["JA1ABC"] == [s["call"] for s in second["spots"]]
    said = [r.getMessage() for r in caplog.records if "T88AB" in r.getMessage()]
    assert len(said) == 1 and "left out of the spots list" in said[0], said
