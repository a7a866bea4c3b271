"""TleCatalog (sky/catalog.py): satellites by name from ``[tracking] tle_file``, re-read when
the file changes. The element sets are written here (tests/support/sky.py's synthetic_tle,
checksums computed there from Celestrak's format), so what a lookup returns is checked against
lines the test made, never against the parser's own output."""

from __future__ import annotations

import logging
import os
import threading
from pathlib import Path

import pytest

from bridge.core.model import ErrorKind, TrackBody
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.sky import Body, Sky
from bridge.sky import catalog as catalog_module
from bridge.sky.catalog import MAX_FILE_BYTES, CatalogError, TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.virtual import VirtualRotator
from tests.support.sky import synthetic_tle
from tests.support.waiting import refusal_beside_a_fifo

EPOCH = 1767225600.0  # 2026-01-01 00:00 UTC: a fixed epoch, so every run reads the same lines


def tle(catalog: int, raan_deg: float = 0.0) -> tuple[str, str]:
    return synthetic_tle(
        "", EPOCH, inclination_deg=51.6, raan_deg=raan_deg, mean_anomaly_deg=0.0, catalog=catalog
    )


ISS = tle(25544)
NOAA = tle(33591, 40.0)
AO7 = tle(7530, 80.0)
BARE = tle(5, 120.0)  # catalog 00005, no name line


def three_line(*sets: tuple[str, tuple[str, str]]) -> str:
    return "".join(f"{name}\n{l1}\n{l2}\n" for name, (l1, l2) in sets)


@pytest.fixture
def tle_file(tmp_path: Path) -> Path:
    path = tmp_path / "active.txt"
    path.write_text(three_line(("ISS (ZARYA)", ISS), ("NOAA 19", NOAA)))
    return path


def test_a_satellite_is_found_by_name_ignoring_case_and_surrounding_blanks(tle_file: Path) -> None:
    catalog = TleCatalog(tle_file)
    want = Body.satellite("ISS (ZARYA)", *ISS)
    for asked in ("ISS (ZARYA)", "iss (zarya)", "  Iss (Zarya)\t", "ISS (ZARYA)\n"):
        assert catalog.lookup(asked) == want, asked
    assert catalog.lookup("noaa 19") == Body.satellite("NOAA 19", *NOAA)
    # only surrounding blanks: the name's own blank is part of it
    with pytest.raises(CatalogError):
        catalog.lookup("NOAA19")


def test_a_satellite_is_found_by_its_catalog_number_with_or_without_leading_zeros(
    tmp_path: Path,
) -> None:
    path = tmp_path / "sats.txt"
    bare = f"{BARE[0]}\n{BARE[1]}\n"  # a 2-line set: named by its catalog number, "00005"
    path.write_text(three_line(("ISS (ZARYA)", ISS), ("AO-7", AO7)) + bare)
    catalog = TleCatalog(path)
    iss = Body.satellite("ISS (ZARYA)", *ISS)
    assert catalog.lookup("25544") == catalog.lookup(" 025544 ") == iss
    ao7 = Body.satellite("AO-7", *AO7)
    assert catalog.lookup("7530") == catalog.lookup("07530") == catalog.lookup("0007530") == ao7
    bare_body = Body.satellite("00005", *BARE)
    for asked in ("5", "05", "00005"):
        assert catalog.lookup(asked) == bare_body, asked
    assert catalog.names() == ["00005", "AO-7", "ISS (ZARYA)"]


def test_an_unknown_name_is_refused_naming_the_file_and_how_many_it_holds(tmp_path: Path) -> None:
    path = tmp_path / "two.txt"
    path.write_text(f"{ISS[0]}\n{ISS[1]}\n{NOAA[0]}\n{NOAA[1]}\n")  # two bare sets
    with pytest.raises(CatalogError) as err:
        TleCatalog(path).lookup("HUBBLE")
    assert str(err.value) == f"no satellite 'HUBBLE' in {path} (2 satellites)"
    with pytest.raises(CatalogError, match="in .*two.txt"):
        TleCatalog(path).lookup("99999")  # a catalog number that is not there


def test_no_tle_file_configured_suggests_sending_the_elements_as_json() -> None:
    catalog = TleCatalog(None)
    with pytest.raises(CatalogError) as err:
        catalog.lookup("ISS")
    message = str(err.value)
    assert "'ISS'" in message and "[tracking] tle_file" in message
    assert '{"tle": ["NAME", "1 ...", "2 ..."]}' in message
    assert catalog.names() == []


def test_a_missing_file_has_no_satellites_until_it_appears(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / "later.txt"
    catalog = TleCatalog(path)
    with caplog.at_level(logging.WARNING, logger="bridge.sky.catalog"):
        assert catalog.names() == []
        with pytest.raises(CatalogError, match=r"\(0 satellites\)"):
            catalog.lookup("ISS (ZARYA)")
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(said) == 1 and str(path) in said[0] and "cannot be read" in said[0], said
    path.write_text(three_line(("ISS (ZARYA)", ISS)))  # cron's first refresh
    assert catalog.lookup("iss (zarya)") == Body.satellite("ISS (ZARYA)", *ISS)
    assert catalog.names() == ["ISS (ZARYA)"]


def test_a_rewritten_file_is_read_again_whether_its_size_or_only_its_time_changed(
    tle_file: Path,
) -> None:
    catalog = TleCatalog(tle_file)
    assert catalog.names() == ["ISS (ZARYA)", "NOAA 19"]
    # a refresh with one more satellite: the size changes
    tle_file.write_text(three_line(("ISS (ZARYA)", ISS), ("NOAA 19", NOAA), ("AO-7", AO7)))
    assert catalog.lookup("ao-7") == Body.satellite("AO-7", *AO7)
    # the same length, other names: only the modification time tells
    before = tle_file.stat()
    tle_file.write_text(three_line(("ISS (ZARYA)", ISS), ("NOAA 18", NOAA), ("AO-8", AO7)))
    assert tle_file.stat().st_size == before.st_size
    os.utime(tle_file, ns=(before.st_atime_ns, before.st_mtime_ns + 1_000_000_000))
    assert catalog.names() == ["AO-8", "ISS (ZARYA)", "NOAA 18"]
    with pytest.raises(CatalogError):
        catalog.lookup("NOAA 19")
    assert catalog.lookup("noaa 18") == Body.satellite("NOAA 18", *NOAA)


def test_a_file_read_once_is_not_read_again_while_unchanged(tle_file: Path) -> None:
    """Rule 1: it is the size and time that say "changed": a rewrite that keeps both (which no
    real refresh does) is not seen, proving the lookups do not re-read the file every time."""
    catalog = TleCatalog(tle_file)
    assert catalog.names() == ["ISS (ZARYA)", "NOAA 19"]
    before = tle_file.stat()
    tle_file.write_text(three_line(("ISS (ZARYA)", ISS), ("NOAA 18", NOAA)))
    os.utime(tle_file, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert catalog.names() == ["ISS (ZARYA)", "NOAA 19"]


def test_a_file_that_goes_away_keeps_the_satellites_last_read(
    tle_file: Path, caplog: pytest.LogCaptureFixture
) -> None:
    catalog = TleCatalog(tle_file)
    assert catalog.names() == ["ISS (ZARYA)", "NOAA 19"]
    tle_file.unlink()  # a refresh in progress (or a broken cron job)
    with caplog.at_level(logging.WARNING, logger="bridge.sky.catalog"):
        assert catalog.lookup("ISS (ZARYA)") == Body.satellite("ISS (ZARYA)", *ISS)
        assert catalog.names() == ["ISS (ZARYA)", "NOAA 19"]
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(said) == 1 and "cannot be read" in said[0], said  # said once, not per lookup


def test_a_bad_set_is_skipped_with_a_warning_naming_its_line(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / "one-bad.txt"
    l1, l2 = NOAA
    broken = l2[:68] + str((int(l2[68]) + 1) % 10)  # a wrong checksum on line 2 of NOAA 19
    path.write_text(three_line(("ISS (ZARYA)", ISS), ("NOAA 19", (l1, broken)), ("AO-7", AO7)))
    with caplog.at_level(logging.WARNING, logger="bridge.sky.catalog"):
        catalog = TleCatalog(path)
        assert catalog.names() == ["AO-7", "ISS (ZARYA)"]
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(said) == 1, said
    assert str(path) in said[0] and "line 6" in said[0] and "NOAA 19" in said[0], said
    assert "checksum" in said[0], said
    with pytest.raises(CatalogError):
        catalog.lookup("NOAA 19")
    assert catalog.lookup("AO-7") == Body.satellite("AO-7", *AO7)


def test_names_are_sorted_and_each_once(tmp_path: Path) -> None:
    path = tmp_path / "dup.txt"
    # NOAA 19 twice (a file concatenated from two sources): the later set is used, named once
    path.write_text(
        three_line(("NOAA 19", tle(33591, 10.0)), ("AO-7", AO7), ("ISS (ZARYA)", ISS))
        + three_line(("NOAA 19", NOAA))
    )
    catalog = TleCatalog(path)
    assert catalog.names() == ["AO-7", "ISS (ZARYA)", "NOAA 19"]
    assert catalog.lookup("NOAA 19") == Body.satellite("NOAA 19", *NOAA)


def test_the_count_is_of_satellites_not_of_lookup_keys(tmp_path: Path) -> None:
    path = tmp_path / "active.txt"
    path.write_text(three_line(("ISS (ZARYA)", ISS), ("NOAA 19", NOAA)))
    with pytest.raises(CatalogError, match=r"\(2 satellites\)"):
        TleCatalog(path).lookup("HUBBLE")


def test_a_name_of_digits_with_a_leading_zero_is_found_by_name(tmp_path: Path) -> None:
    path = tmp_path / "digits.txt"
    path.write_text(three_line(("0815", ISS)))
    assert TleCatalog(path).lookup("0815").name == "0815"
    assert TleCatalog(path).lookup("25544").name == "0815"  # and by its catalog number


# -- a large or broken file (review: a 210 MB garbage file held paho's thread 35.9 s) ---------
def garbage(lines: int) -> str:
    """Lines that look like TLE lines but pair with nothing: every one is a problem."""
    return "".join(f"1 {n:05d}U garbage line {n}\n" for n in range(lines))


def test_bad_lines_are_counted_in_one_warning_per_read(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / "broken.txt"
    path.write_text(garbage(5000) + three_line(("ISS (ZARYA)", ISS)))
    with caplog.at_level(logging.WARNING, logger="bridge.sky.catalog"):
        catalog = TleCatalog(path)
        assert catalog.lookup("ISS (ZARYA)") == Body.satellite("ISS (ZARYA)", *ISS)
        assert catalog.names() == ["ISS (ZARYA)"]  # read once: no second warning
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(said) == 1, said[:3]
    assert "5000 bad entries skipped" in said[0] and str(path) in said[0], said
    assert "line 1:" in said[0]  # the first, to start looking


def test_a_file_over_the_limit_is_not_read_and_a_lookup_says_why(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "huge.txt"
    with path.open("w") as f:
        f.truncate(MAX_FILE_BYTES + 1)  # sparse: 4 MiB and a byte of nothing
    parsed: list[int] = []
    monkeypatch.setattr(catalog_module, "parse_tles", lambda text: parsed.append(1) or ({}, []))
    with caplog.at_level(logging.WARNING, logger="bridge.sky.catalog"):
        catalog = TleCatalog(path)
        for _ in range(3):
            with pytest.raises(CatalogError) as err:
                catalog.lookup("ISS")
            assert str(path) in str(err.value) and "4 MiB" in str(err.value), err.value
    assert parsed == []  # never read
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(said) == 1 and "4 MiB" in said[0], said


def test_track_by_name_returns_before_the_file_is_read_and_is_refused_later(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """R/track on paho's thread only queues the name: the sky worker reads the file."""
    path = tmp_path / "garbage.txt"
    path.write_text(garbage(20000))
    readers: list[str] = []
    real_parse = catalog_module.parse_tles

    def parse(text: str) -> tuple[dict[str, tuple[str, str]], list[str]]:
        readers.append(threading.current_thread().name)
        return real_parse(text)

    monkeypatch.setattr(catalog_module, "parse_tles", parse)
    with VirtualRotator("md01", sky=Sky(52.52, 13.29)) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        rot = Rotator(v.cfg, StateStore(None), lambda s: None, lambda e: None)
        # the rotator's front half (what paho's thread runs) on the bench's session and mailbox
        rot._mailbox, rot._worker.session = v.mailbox, v.session
        rot.catalog = TleCatalog(path)
        rot.submit(TrackBody("ISS"), "track 'ISS'")
        assert readers == []  # returned: nothing read on the calling thread
        v._take()  # the lines thread takes the command: the look-up goes to the sky worker
        questions = [a.question for _t, a in v.asked]
        assert [type(q) for q in questions] == [LookupQuestion], questions
        v.run_for(1.0)
    assert readers == [threading.current_thread().name]  # the bench plays the sky worker
    refused = v.errors(ErrorKind.REFUSED)
    assert len(refused) == 1 and refused[0].command == "track 'ISS'", refused
    assert f"no satellite 'ISS' in {path} (0 satellites)" == refused[0].message


# -- what is no regular file (attack 18: /dev/zero read to the limit, a FIFO held the lock) ----
def test_a_device_is_not_read_and_a_lookup_says_why(caplog: pytest.LogCaptureFixture) -> None:
    """Rule 4: /dev/zero (of size 0) was read to the 4 MiB limit and its one line quoted whole,
    16 MB in one warning."""
    catalog = TleCatalog(Path("/dev/zero"))
    with caplog.at_level(logging.WARNING, logger="bridge.sky.catalog"):
        for _ in range(3):
            with pytest.raises(CatalogError, match="no regular file") as err:
                catalog.lookup("ISS")
            assert "/dev/zero" in str(err.value), err.value
        assert catalog.names() == []
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert said == [
        "tle_file /dev/zero is no regular file (a device, a pipe or a folder): not read"
    ]


def test_a_fifo_nobody_writes_holds_no_lookup(tmp_path: Path) -> None:
    """Rule 4: a FIFO's open waited for a writer, under the catalog's lock: every lookup behind
    it, the sky worker's and the names for Home Assistant, waited for ever."""
    fifo = tmp_path / "active.txt"
    os.mkfifo(fifo)
    catalog = TleCatalog(fifo)
    said = [refusal_beside_a_fifo(fifo, lambda: catalog.lookup("ISS"), CatalogError)]
    assert said == [
        f"no satellite 'ISS': tle_file {fifo} is no regular file (a device, a pipe "
        "or a folder): not read"
    ]


def test_a_file_of_one_secret_line_is_said_without_quoting_it(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Attack 18, whatever the settings know of the file (a token of another program's named
    by mistake): its one line is no satellite's name, and the warning never quotes it."""
    path = tmp_path / "token"
    path.write_text("Wr1tten-0nly-1n-the-token-file\n")
    with caplog.at_level(logging.WARNING, logger="bridge.sky.catalog"):
        assert TleCatalog(path).names() == []
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert said == [
        f"tle_file {path}: 1 bad entry skipped (the first: line 1: a line of 30 characters is "
        "not followed by a TLE)"
    ]
