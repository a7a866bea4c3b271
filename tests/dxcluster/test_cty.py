"""AD1C's country files parsed (a small file written in their formats): the longitude's sign,
the prefix overrides, exact calls, and how a call with a portable part is looked up."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from bridge.interfaces.dxcluster.cty import CTY_FILE_MAX, Cty, CtyError, load, parse_csv, parse_dat
from tests.dxcluster.cty_sample import CTY_CSV, CTY_DAT
from tests.support.waiting import refusal_beside_a_fifo


@pytest.fixture(params=["dat", "csv"])
def cty(request: pytest.FixtureRequest) -> Cty:
    return parse_dat(CTY_DAT) if request.param == "dat" else parse_csv(CTY_CSV)


def test_longitudes_become_east_positive(cty: Cty) -> None:
    japan = cty.lookup("JA1ABC")
    assert japan is not None
    assert (japan.name, japan.continent, japan.prefix) == ("Japan", "AS", "JA")
    assert (japan.latitude_deg, japan.longitude_deg) == (36.40, 138.38)  # east of Greenwich
    usa = cty.lookup("W2XYZ")
    assert usa is not None and usa.longitude_deg == -91.67  # west
    assert cty.lookup("F5ABC").longitude_deg == 2.00  # type: ignore[union-attr]


def test_the_longest_prefix_wins_and_exact_calls_come_first(cty: Cty) -> None:
    assert cty.lookup("JR7AAA").name == "Japan"  # type: ignore[union-attr]
    assert cty.lookup("2E0ABC").name == "England"  # type: ignore[union-attr]
    assert cty.lookup("M0ABC").name == "England"  # type: ignore[union-attr]
    exact = cty.lookup("VK9XX")
    assert exact is not None
    assert (exact.cq_zone, exact.itu_zone, exact.continent) == (29, 54, "AS")
    assert (exact.latitude_deg, exact.longitude_deg) == (-10.50, 105.70)  # the override's sign
    assert cty.lookup("VK9XY").cq_zone == 30  # type: ignore[union-attr]  # not the exact call
    assert cty.lookup("jA1xyz/jd1").latitude_deg == 27.10  # type: ignore[union-attr]
    assert cty.lookup("W1AW/KH6").name == "United States"  # type: ignore[union-attr]
    assert cty.lookup("QQ1ABC") is None


def test_portable_forms(cty: Cty) -> None:
    assert cty.lookup("JA1ABC/P").name == "Japan"  # type: ignore[union-attr]
    assert cty.lookup("JA1ABC/QRP").name == "Japan"  # type: ignore[union-attr]
    assert cty.lookup("G4ABC/M").name == "England"  # type: ignore[union-attr]
    assert cty.lookup("G4ABC/7").name == "England"  # type: ignore[union-attr]
    assert cty.lookup("F/G4ABC").name == "France"  # type: ignore[union-attr]  # the prefix
    assert cty.lookup("G4ABC/F").name == "France"  # type: ignore[union-attr]
    assert cty.lookup("F/G4ABC/P").name == "France"  # type: ignore[union-attr]
    assert cty.lookup("F/G4ABC/9").name == "France"  # type: ignore[union-attr]  # rule 3a
    assert cty.lookup("W1XYZ/4").name == "United States"  # type: ignore[union-attr]  # W4
    assert cty.lookup("G4ABC/MM") is None  # maritime mobile: no entity
    assert cty.lookup("/") is None
    assert cty.lookup("") is None


def test_a_call_area_is_looked_up_in_that_area_not_by_the_home_calls_exact_entry() -> None:
    """Rule 3a: ``/9`` is the call area the station is in: the home call's own exact entry
    (an operator listed at home, far from the entity's centre) is not where it is now; an
    exact entry of the whole form is."""
    cty = parse_dat(
        "European Russia:  16:  29:  EU:   53.65:  -41.37:  -4.0:  UA:\n"
        "    UA,UA3,=UA3ABC<44.00/-39.00>,=UA3XYZ/9<60.00/-30.00>;\n"
        "Asiatic Russia:   17:  30:  AS:   55.88:  -84.08:  -7.0:  UA9:\n"
        "    UA9,UA0;\n"
    )
    home = cty.lookup("UA3ABC")
    assert home is not None and home.latitude_deg == 44.00  # the exact entry, at home
    away = cty.lookup("UA3ABC/9/P")
    assert away is not None and (away.name, away.latitude_deg) == ("Asiatic Russia", 55.88)
    listed = cty.lookup("UA3XYZ/9")
    assert listed is not None and (listed.name, listed.latitude_deg) == ("European Russia", 60.0)
    assert cty.lookup("UA9ABC/0").name == "Asiatic Russia"  # type: ignore[union-attr]


def test_odd_lines_are_skipped_and_counted() -> None:
    cty = parse_dat("garbage without colons\n" + CTY_DAT + "  stray,prefixes;\n")
    assert cty.lookup("JA1ABC") is not None
    assert cty.skipped == 2
    csv = parse_csv("JA,Japan,339,AS,x,45,36.40,-138.38,-9.0,JA;\n" + CTY_CSV)
    assert csv.skipped == 1 and csv.lookup("JA1ABC") is not None


def test_load_tells_the_formats_apart_and_names_a_bad_file(tmp_path: Path) -> None:
    (tmp_path / "cty.dat").write_text(CTY_DAT)
    (tmp_path / "cty.csv").write_text(CTY_CSV)
    for name in ("cty.dat", "cty.csv"):
        assert load(tmp_path / name).lookup("VK2ABC").name == "Australia"  # type: ignore[union-attr]
    with pytest.raises(CtyError, match="missing.dat cannot be read"):
        load(tmp_path / "missing.dat")
    (tmp_path / "empty.dat").write_bytes(b"\xff\xfe nothing here\n")
    with pytest.raises(CtyError, match="empty.dat: no entity"):
        load(tmp_path / "empty.dat")


def test_what_is_no_regular_file_or_too_large_is_not_read(tmp_path: Path) -> None:
    """Rule 4 (attack 18): /dev/zero was read until the memory ran out; a file over the limit
    is refused before it is parsed, naming the limit."""
    with pytest.raises(CtyError, match="/dev/zero cannot be read: it is no regular file"):
        load(Path("/dev/zero"))
    huge = tmp_path / "cty.dat"
    huge.write_text(CTY_DAT)
    with huge.open("r+") as f:
        f.truncate(CTY_FILE_MAX + 1)  # sparse: a good file, then nothing to the limit and a byte
    with pytest.raises(CtyError, match="cty.dat cannot be read: it is larger than 16 MiB"):
        load(huge)


def test_a_fifo_nobody_writes_holds_no_start(tmp_path: Path) -> None:
    """Rule 4 (attack 18): a FIFO's open waited for a writer: the start, for ever."""
    fifo = tmp_path / "cty.dat"
    os.mkfifo(fifo)
    said = [refusal_beside_a_fifo(fifo, lambda: load(fifo), CtyError)]
    assert said == [
        f"cty_file {fifo} cannot be read: it is no regular file (a device, a pipe or a folder): "
        "name AD1C's cty.dat or cty.csv"
    ]


def test_what_is_refused_is_quoted_cut_short() -> None:
    """Rule 5 (attack 18): a name or a number of a megabyte is no megabyte in the log."""
    name, lat = "P" * 1_000_000, "9" * 100_000
    cty = parse_dat(CTY_DAT + f"{name}:  27:  64:  OC:   {lat}:  -134.53:    -9.0:  T8:\n    T8;\n")
    assert cty.refused == [
        f"line 12: {'P' * 40!r}… (1000000 characters): latitude {'9' * 40!r}… (100000 "
        "characters) is no place's (-90..90); its calls are placed nowhere"
    ]


def test_lighthouse_rover_and_beacon_suffixes_name_no_entity() -> None:
    """``/LH`` and ``/LGT`` (a lighthouse activation), ``/R`` (a VHF contest rover) and ``/B``
    (a beacon) say what the station is, not where: read as the shorter part they were
    prefixes of Norway (LH), Russia (R) and China (B), and the rotor turned there."""
    cty = parse_dat(
        CTY_DAT
        + "Norway:                   14:  18:  EU:   61.00:   -9.00:    -1.0:  LA:\n"
        + "    LA,LB,LC,LD,LE,LF,LG,LH,LI,LJ,LK,LL,LM,LN;\n"
        + "European Russia:          16:  29:  EU:   53.65:  -41.37:    -4.0:  UA:\n"
        + "    R,U,UA;\n"
        + "China:                    24:  44:  AS:   36.00:  -102.00:   -8.0:  BY:\n"
        + "    B,BY;\n"
    )
    assert cty.lookup("G4ABC/LH").name == "England"  # type: ignore[union-attr]
    assert cty.lookup("G4ABC/LGT").name == "England"  # type: ignore[union-attr]
    assert cty.lookup("W1ABC/R").name == "United States"  # type: ignore[union-attr]
    assert cty.lookup("W1ABC/B").name == "United States"  # type: ignore[union-attr]
    assert cty.lookup("LA1ABC").name == "Norway"  # type: ignore[union-attr]  # still prefixes
    assert cty.lookup("R1ABC").name == "European Russia"  # type: ignore[union-attr]
