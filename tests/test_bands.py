"""The band table (bridge/core/bands.py): a frequency as each program sends it names its band, edges
included, whatever IARU region the station is in; a band name in any case is the table's, and
one that is not gets the nearest names."""

from __future__ import annotations

import math

import pytest

from bridge.core.bands import NAMES, UnknownBand, band_of_hz, band_of_mhz, canonical


@pytest.mark.parametrize(
    ("hz", "band"),
    [
        (14_074_000, "20m"),  # WSJT-X's FT8 dials
        (7_074_000, "40m"),
        (21_074_000, "15m"),
        (28_074_000, "10m"),
        (50_313_000, "6m"),
        (144_174_000, "2m"),
        (1_840_000, "160m"),
        (5_357_000, "60m"),
        (10_136_000, "30m"),
        (18_100_000, "17m"),
        (24_915_000, "12m"),
        (475_700, "630m"),
        (136_000, "2190m"),
        (14_000_000, "20m"),  # both edges belong to the band
        (14_350_000, "20m"),
        (7_250_000, "40m"),  # Region 2's 40 m, above Region 1's 7.2 MHz
        (3_900_000, "80m"),  # Region 2's and 3's 80 m
        (146_520_000, "2m"),  # Region 2's 2 m, above Region 1's 146 MHz
        (432_100_000, "70cm"),
        (1_296_200_000, "23cm"),
        (10_368_100_000, "3cm"),
    ],
)
def test_a_dial_frequency_names_its_band(hz: int, band: str) -> None:
    assert band_of_hz(hz) == band


@pytest.mark.parametrize("hz", [13_999_999, 14_350_001, 9_000_000, 100_000_000, 0, -14_074_000])
def test_a_frequency_outside_every_band_names_none(hz: int) -> None:
    assert band_of_hz(hz) is None


@pytest.mark.parametrize("x", [math.nan, math.inf, -math.inf])
def test_a_number_that_is_no_number_names_no_band(x: float) -> None:
    assert band_of_hz(x) is None and band_of_mhz(x) is None


@pytest.mark.parametrize(
    ("mhz", "band"),
    [
        (1.8, "160m"),  # what N1MM writes in <freqband>: the fact sheet's examples
        (3.5, "80m"),
        (7, "40m"),
        (14, "20m"),
        (21.0, "15m"),
        (28.0, "10m"),
        (10, "30m"),  # round numbers below their band's lower edge
        (18, "17m"),
        (24, "12m"),
        (5, "60m"),
        (50, "6m"),
        (144, "2m"),
        (432, "70cm"),
        (1296, "23cm"),
        (0.472, "630m"),
        (0.136, "2190m"),
        (14.074, "20m"),  # a frequency inside the band, for a sender that gives one
    ],
)
def test_n1mms_band_field_names_its_band(mhz: float, band: str) -> None:
    assert band_of_mhz(mhz) == band


@pytest.mark.parametrize("mhz", [12.0, 0.0, 100.0, 9.0, 4.5, -14.0])
def test_an_n1mm_band_field_that_is_no_band_names_none(mhz: float) -> None:
    assert band_of_mhz(mhz) is None


def test_bands_do_not_overlap_and_are_in_order() -> None:
    from bridge.core.bands import BANDS

    for lower, upper in zip(BANDS, BANDS[1:], strict=False):
        assert lower.low_hz < lower.high_hz < upper.low_hz, (lower, upper)
    assert len(set(NAMES)) == len(NAMES)


@pytest.mark.parametrize(("given", "name"), [("20m", "20m"), ("20M", "20m"), (" 70CM ", "70cm")])
def test_a_band_name_in_any_case_is_the_tables(given: str, name: str) -> None:
    assert canonical(given) == name


@pytest.mark.parametrize(
    ("given", "meant"),
    [("20", "'20m'"), ("15 m", "'15m'"), ("2om", "'20m'"), ("70 cm", "'70cm'")],
)
def test_an_unknown_band_name_says_what_was_meant(given: str, meant: str) -> None:
    with pytest.raises(UnknownBand, match="did you mean") as caught:
        canonical(given)
    assert meant in str(caught.value) and "is not an amateur band" in str(caught.value)


def test_a_name_nothing_is_near_lists_the_bands() -> None:
    with pytest.raises(UnknownBand) as caught:
        canonical("shortwave")
    assert "did you mean" not in str(caught.value) and "160m" in str(caught.value)
