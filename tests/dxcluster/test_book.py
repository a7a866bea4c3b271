"""The spots kept (book.py), in virtual time: the position (a locator in the comment first, the
cty entity else), the band filter, the newest max_spots, the age limit, the JSON."""

from __future__ import annotations

import json

from bridge.core import geo
from bridge.interfaces.dxcluster.book import MAX_CALLS, Book, locator_in
from bridge.interfaces.dxcluster.cty import parse_dat
from bridge.interfaces.dxcluster.spots import Spot
from bridge.settings.dxcluster import DxClusterSettings
from tests.dxcluster.cty_sample import CTY_DAT
from tests.integration.test_pointing_bridge import locator_centre, reference_path
from tests.support.clock import FakeClock, wall_at

STATION = "JO62QM"


def spot(call: str, freq_khz: float = 14025.0, comment: str = "") -> Spot:
    return Spot(call, freq_khz, "G4ABC", "1234", comment)


def book(clock: FakeClock, **kw: object) -> Book:
    station = locator_centre(STATION)
    return Book(parse_dat(CTY_DAT), station, clock=clock, wall=lambda: wall_at("1234"), **kw)  # type: ignore[arg-type]


def test_locators_in_comments() -> None:
    assert locator_in("FT8 -12 dB FN31pr") == "FN31PR"
    assert locator_in("JO01<>FN31 tnx") == "FN31"  # the one after >: the DX's
    assert locator_in("JO01<ES>FN31") == "FN31"
    assert locator_in("FT8 RR73 JN58") == "JN58"  # RR73 is a sign-off
    assert locator_in("RR73") is None
    assert locator_in("cq up 2 FT8 +03") is None
    assert locator_in("AB12CD34X") is None  # too long: no locator
    assert locator_in("tnx io91") == "IO91"


def test_positions_bearings_and_the_json() -> None:
    clock = FakeClock()
    b = book(clock)
    assert b.add(spot("JA1ABC"))
    assert b.add(spot("W1XYZ", 50313.0, "FT8 JO01<>FN31pr"))
    assert b.add(spot("QQ1ABC"))  # in no entity: kept, without a position
    doc = json.loads(b.as_json())["spots"]
    assert [s["call"] for s in doc] == ["QQ1ABC", "W1XYZ", "JA1ABC"]  # newest first
    assert doc[0]["position"] is None and "bearing_deg" not in doc[0]
    w1, ja = doc[1], doc[2]
    assert (w1["position"], w1["locator"], w1["band"]) == ("locator", "FN31PR", "6m")
    assert (ja["position"], ja["entity"], ja["band"]) == ("cty", "Japan", "20m")
    assert ja["longitude"] == 138.38  # east: cty.dat's west-positive sign converted
    for s, where in ((w1, locator_centre("FN31PR")), (ja, (36.40, 138.38))):
        want, km = reference_path(locator_centre(STATION), where)
        assert abs((s["bearing_deg"] - want + 180) % 360 - 180) <= 0.1
        assert abs((s["long_path_deg"] - want - 180 + 180) % 360 - 180) <= 0.1
        assert abs(s["distance_km"] - km) <= 0.01 * km
    assert ja["time"] == "1234Z" and ja["heard"] == "2026-01-01T12:34:00Z"
    assert ja["frequency_khz"] == 14025.0 and ja["spotter"] == "G4ABC"


def test_without_a_station_there_is_no_bearing() -> None:
    b = Book(parse_dat(CTY_DAT), None, wall=lambda: wall_at("1234"))
    b.add(spot("JA1ABC"))
    (only,) = json.loads(b.as_json())["spots"]
    assert only["position"] == "cty" and "bearing_deg" not in only


def test_bands_count_and_age() -> None:
    clock = FakeClock()
    b = book(clock, bands=("20m", "40m"), max_spots=3, max_age_s=600.0)
    assert not b.add(spot("JA1ABC", 144300.0))  # 2m: not asked for
    assert not b.add(spot("JA1ABC", 12345.0))  # no band
    for i, call in enumerate(["JA1AAA", "JA1BBB", "JA1CCC", "JA1DDD"]):
        clock.t += 60.0
        b.add(spot(call, 7000.0 + i))
    assert b.calls() == ("JA1DDD", "JA1CCC", "JA1BBB")  # the newest three
    b.add(spot("JA1CCC", 7030.0))  # again on the same band: it replaces the older one
    assert b.calls() == ("JA1CCC", "JA1DDD", "JA1BBB")
    b.add(spot("JA1CCC", 14030.0))  # on another band: both kept
    assert b.calls() == ("JA1CCC", "JA1DDD")
    newest = b.newest("ja1ccc")
    assert newest is not None and newest.spot.freq_khz == 14030.0
    assert not b.prune()
    clock.t += 600.0 - 1  # the three kept were heard 599 s ago: young enough
    assert not b.prune() and len(b.calls()) == 2
    clock.t += 2.0
    assert b.prune()
    assert b.calls() == () and b.newest("JA1CCC") is None
    assert json.loads(b.as_json()) == {"spots": []}


def test_the_bands_are_the_rotators_and_the_loggers_table() -> None:
    """settings/dxcluster.py rule 3: one table of bands (core/bands.py), so a spot is on the
    band a rotator's ``bands`` means: 23 cm and 1.25 m are bands; 70.6 MHz is no 4 m."""
    settings = DxClusterSettings(bands=["23CM", "1.25m", "70cm", "4m"])
    assert settings.bands == ["23cm", "1.25m", "70cm", "4m"]
    b = book(FakeClock(), bands=tuple(settings.bands))
    assert b.add(spot("JA1AAA", 1296200.0))
    assert b.add(spot("JA1BBB", 222100.0))
    assert b.add(spot("JA1CCC", 445000.0))  # Region 2's 70 cm
    assert not b.add(spot("JA1DDD", 70600.0))  # above 4 m's widest edge (70.5 MHz)
    assert {s["band"] for s in json.loads(b.as_json())["spots"]} == {"23cm", "1.25m", "70cm"}


def test_the_calls_are_bounded() -> None:
    b = book(FakeClock(), max_spots=200)
    for i in range(MAX_CALLS + 10):
        b.add(spot(f"JA1A{i:02d}"))
    assert len(b.calls()) == MAX_CALLS


def test_a_spot_with_no_direction_has_no_bearing() -> None:
    """At the station's own place, or at its antipode, every bearing is as good as another
    (geo: ``has_direction`` False): B/spots said ``0.0`` as if due north, and a dashboard
    showed it as one; null, as without a station."""
    here = geo.parse_locator("JO62QM")
    there = (-here[0], here[1] - 180.0)  # the antipode
    book = Book(None, here, wall=lambda: wall_at("1830"))
    book.add(Spot("DL1ABC", 14025.0, "EA5WU", "1829", "JO62QM"))
    book.add(Spot("ZL1ABC", 7025.0, "EA5WU", "1830", "RE78"))
    spots = {s["call"]: s for s in json.loads(book.as_json())["spots"]}
    assert spots["DL1ABC"]["bearing_deg"] is None
    assert spots["DL1ABC"]["distance_km"] == 0
    book = Book(None, there, wall=lambda: wall_at("1830"))
    book.add(Spot("DL1ABC", 14025.0, "EA5WU", "1829", "JO62QM"))
    assert json.loads(book.as_json())["spots"][0]["bearing_deg"] is None


def at(call: str, hhmm: str, comment: str = "", freq_khz: float = 14025.0) -> Spot:
    return Spot(call, freq_khz, "EA5WU", hhmm, comment)


def test_the_newer_spot_of_a_call_by_its_own_time_is_kept_whatever_came_last() -> None:
    """Rule 2, attack 13: a node replays its last spots at a login; the older spot of a call,
    coming after the newer one, neither takes its place nor moves ahead of newer spots."""
    clock, now = FakeClock(), [wall_at("1837")]
    b = Book(parse_dat(CTY_DAT), locator_centre(STATION), clock=clock, wall=lambda: now[0])
    assert b.add(at("W6XYZ", "1829"))  # no locator: the cty entity
    assert b.add(at("W6XYZ", "1835", "FT8 CM87"))
    assert b.add(at("JA1ABC", "1836"))
    assert not b.add(at("W6XYZ", "1829"))  # the login's replay
    assert not b.add(at("W6XYZ", "1830", "FN31"))  # an older one never seen before: no better
    kept = b.newest("W6XYZ")
    assert kept is not None and kept.place is not None and kept.place.locator == "CM87"
    assert b.add(at("G4XYZ", "1820"))  # a replayed spot of another call: behind the newer
    doc = json.loads(b.as_json())["spots"]
    assert [(s["call"], s["time"]) for s in doc] == [
        ("JA1ABC", "1836Z"),
        ("W6XYZ", "1835Z"),
        ("G4XYZ", "1820Z"),
    ]
    assert b.add(at("W6XYZ", "1835", "cq"))  # the same minute, heard later: the later word
    assert json.loads(b.as_json())["spots"][1]["comment"] == "cq"


def test_a_spot_is_as_old_as_its_own_time_says() -> None:
    """Rule 2, attack 13: a spot replayed after it aged out came back for another
    max_age_min; one older than max_age_s by its own time is not taken, and a younger one
    leaves when its own time is max_age_s old."""
    clock = FakeClock(0.0)
    b = Book(None, None, max_age_s=1800.0, clock=clock, wall=lambda: wall_at("1910") + clock.t)
    assert not b.add(at("JA1ABC", "1839"))  # 31 minutes old: gone already
    assert b.too_old == 1
    assert b.add(at("JA1ABC", "1841"))  # 29 minutes old: one minute left
    assert b.add(at("VK2XYZ", "1910"))
    clock.t += 60.0
    assert not b.prune()
    clock.t += 1.0
    assert b.prune()
    assert b.calls() == ("VK2XYZ",)
    assert not b.add(at("JA1ABC", "1841"))  # replayed again: it does not come back


def test_midnight() -> None:
    """Rule 2: a spot's day is the bridge's, the day before for a time ahead of the bridge's
    clock by more than SKEW_S (30 minutes); a node's clock ahead across midnight is of the
    next."""
    clock, now = FakeClock(), [wall_at("0002")]
    b = Book(None, None, max_age_s=1800.0, clock=clock, wall=lambda: now[0])
    assert b.add(at("JA1ABC", "2358"))  # four minutes ago, yesterday
    assert b.add(at("JA1ABC", "0001"))  # newer, today
    assert not b.add(at("JA1ABC", "2359"))  # replayed: older
    assert not b.add(at("VK2XYZ", "0040"))  # 38 minutes ahead: yesterday's, 23h22 old
    assert b.add(at("VK2XYZ", "0010"))  # eight minutes ahead: the node's clock, today
    assert b.add(at("ZL1AAA", "0030"))  # 28 minutes ahead (review 56: 5 minutes lost spots)
    now[0] = wall_at("2358")
    b = Book(None, None, max_age_s=1800.0, clock=clock, wall=lambda: now[0])
    assert b.add(at("JA1ABC", "2357"))
    assert b.add(at("JA1ABC", "0001"))  # the node's clock past midnight: tomorrow's, newer
    assert not b.add(at("JA1ABC", "2356"))
    kept = b.newest("JA1ABC")
    assert kept is not None and kept.spot.time == "0001"
