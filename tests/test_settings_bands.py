"""A rotator's ``bands`` (settings/bands.py): known band names in any case, an unknown one a
configuration error naming the key and what was meant, no band shared by two rotators, and one
N1MM name shared only by rotators chosen by band."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.app import worker_config
from bridge.settings import ConfigError, load_settings
from tests.support import ROOT

TWO = (
    '[[rotators]]\nid = "high"\nmodel = "rotorez"\nport = "/dev/ttyUSB0"\n{a}\n'
    '[[rotators]]\nid = "low"\nmodel = "rotorez"\nport = "/dev/ttyUSB1"\n{b}\n'
)


def load(tmp_path: Path, a: str, b: str = "") -> object:
    path = tmp_path / "c.toml"
    path.write_text(TWO.format(a=a, b=b))
    return load_settings(path, environ={})


def test_bands_are_read_in_any_case_and_reach_following(tmp_path: Path) -> None:
    s = load(tmp_path, 'bands = ["20M", "15m", " 10m"]', 'bands = ["40m"]')
    high, low = s.rotators  # type: ignore[attr-defined]
    assert high.bands == ["20m", "15m", "10m"] and low.bands == ["40m"]
    assert worker_config(high).follow.bands == ("20m", "15m", "10m")


def test_no_bands_is_the_default(tmp_path: Path) -> None:
    s = load(tmp_path, "")
    assert s.rotators[0].bands == []  # type: ignore[attr-defined]
    assert worker_config(s.rotators[0]).follow.bands == ()  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("a", "b", "message"),
    [
        (
            'bands = ["20"]',
            "",
            r"rotators\[0\]\.bands.*did you mean .*'20m'",
        ),
        ('bands = ["2om"]', "", r"rotators\[0\]\.bands.*did you mean .*'20m'"),
        ('bands = ["20m", "20M"]', "", r"rotators\[0\]\.bands.*'20m' is given twice"),
        ('bands = ["20m"]', 'bands = ["40m", "20m"]', "'high' and 'low' both have '20m' in bands"),
        (
            'n1mm_rotor_name = "Tower"\nbands = ["20m"]',
            'n1mm_rotor_name = "Tower"',
            "n1mm_rotor_name 'Tower' on one N1MM port: give each its own, or give each of them",
        ),
    ],
)
def test_bands_that_cannot_work_are_refused_naming_the_field(
    tmp_path: Path, a: str, b: str, message: str
) -> None:
    with pytest.raises(ConfigError, match=message):
        load(tmp_path, a, b)


def test_rotators_chosen_by_band_may_share_one_n1mm_name(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        'n1mm_rotor_name = "Tower"\nbands = ["20m", "15m"]',
        'n1mm_rotor_name = "Tower"\nbands = ["40m"]',
    )
    assert [r.n1mm_rotor_name for r in s.rotators] == ["Tower", "Tower"]  # type: ignore[attr-defined]


def test_the_band_map_example_loads() -> None:
    s = load_settings(ROOT / "config" / "band-map.toml", environ={})
    assert [(r.id, r.n1mm_rotor_name, r.bands) for r in s.rotators] == [
        ("high", "Tower", ["20m", "15m", "10m"]),
        ("low", "Tower", ["40m", "80m"]),
    ]
