"""Attack 30: a reading a little past an end of its axis's range is that end; further past is
spoiled (protocols/base.py rule 10), the same in every codec that reads a range.

Each model's slack is at least its spec's ``noise_deg`` (how far a still rotor's readings wander:
resting at an end, that far past it), and a whole-degree pot's is POT_SLACK_DEG, a tenths
sensor's TENTHS_SLACK_DEG: the lines below are each codec's reply at the very edge of its
slack (read as the end) and one step of its resolution beyond it (spoiled, no reading). (A
GS-232's horizon: K3NG's forms say no more than 3 below it, tests/protocols/test_review39_*.)
"""

from __future__ import annotations

import pytest

from bridge.protocols import REGISTRY, easycomm, gs232, prosistel, rc2800
from bridge.protocols.base import (
    POT_SLACK_DEG,
    TENTHS_SLACK_DEG,
    JunkReason,
    JunkReply,
    PositionReply,
    read_in_range,
)
from tests.support import HOW, feed

# model, a reply at the edge of the slack, what it reads as, the same one step further past
EDGES = [
    ("gs232b-az-450", b"AZ=453\r\n", (450.0, None), b"AZ=454\r\n"),
    ("gs232a-az-450", b"+0453\r\n", (450.0, None), b"+0454\r\n"),
    ("gs232b-450", b"AZ=453  EL=010\r\n", (450.0, 10.0), b"AZ=454  EL=010\r\n"),
    ("gs232b", b"AZ=100  EL=183\r\n", (100.0, 180.0), b"AZ=100  EL=184\r\n"),
    ("gs232a", b"+0100+0183\r\n", (100.0, 180.0), b"+0100+0184\r\n"),
    ("prosistel", b"\x02A,?,363,B\r", (360.0, None), b"\x02A,?,364,B\r"),
    ("prosistel-el", b"\x02E,?,093,B\r", (90.0, None), b"\x02E,?,094,B\r"),
    ("prosistel-el-a", b"\x02A,?,093,B\r", (90.0, None), b"\x02A,?,094,B\r"),
    (
        "prosistel-combi",
        b"\x02A,?,3605,B\r\x02B,?,0905,B\r",
        (360.0, 90.0),
        b"\x02A,?,3606,B\r\x02B,?,0900,B\r",
    ),
    (
        "prosistel-combi",
        b"\x02A,?,3600,B\r\x02B,?,0905,B\r",
        (360.0, 90.0),
        b"\x02A,?,3600,B\r\x02B,?,0906,B\r",
    ),
    ("rc2800-az", b"A P=  -0.5 S=9 ST\r", (0.0, None), b"A P=  -0.6 S=9 ST\r"),
    ("rc2800-az", b"A P= 360.5 S=9 ST\r", (360.0, None), b"A P= 360.6 S=9 ST\r"),
    ("easycomm3", b"AZ360.5 EL180.5\n", (360.0, 180.0), b"AZ100.0 EL180.6\n"),
    ("easycomm3-az", b"AZ-0.5\n", (0.0, None), b"AZ-0.6\n"),
]


def _readings(replies: list[object]) -> list[tuple[float, float | None]]:
    return [(r.az_deg, r.el_deg) for r in replies if isinstance(r, PositionReply)]


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize(("model", "within", "want", "beyond"), EDGES)
def test_a_reading_past_an_end_within_the_slack_is_the_end_and_beyond_it_is_spoiled(
    how: str, model: str, within: bytes, want: tuple[float, float | None], beyond: bytes
) -> None:
    codec = REGISTRY[model].codec_factory()
    codec.encode_query()
    assert _readings(feed(codec, within, how)) == [want]
    codec = REGISTRY[model].codec_factory()
    codec.encode_query()
    got = feed(codec, beyond, how)
    assert _readings(got) == [], beyond
    spoiled = [r for r in got if isinstance(r, JunkReply) and r.reason is JunkReason.SPOILED]
    assert spoiled and "position out of range" in spoiled[0].detail


SLACKS = {
    "gs232": gs232.READ_SLACK_DEG,
    "prosistel": prosistel.D_AZIMUTH.slack,
    "prosistel-el": prosistel.D_ELEVATION.slack,
    "prosistel-el-a": prosistel.D_ELEVATION_UNIT_A.slack,
    "prosistel-combi": prosistel.COMBI_TRACK.slack,
    "rc2800": rc2800.READ_SLACK_DEG,
    "easycomm": easycomm.READ_SLACK_DEG,
}


def _slack(model: str) -> float:
    if model in SLACKS:
        return SLACKS[model]
    return next(slack for family, slack in SLACKS.items() if model.startswith(family))


@pytest.mark.parametrize(
    "model", [m for m in REGISTRY if m.startswith(("gs232", "prosistel", "rc2800", "easycomm"))]
)
def test_every_models_slack_covers_its_own_noise_and_follows_its_resolution(model: str) -> None:
    """A still rotor at an end wanders noise_deg past it: never spoiled for that; the slack is
    a pot's in whole degrees, a sensor's in tenths (and then under a whole degree)."""
    spec, slack = REGISTRY[model], _slack(model)
    assert slack >= spec.noise_deg
    assert slack == (POT_SLACK_DEG if spec.whole_degrees else TENTHS_SLACK_DEG)


def test_read_in_range_takes_the_end_only_within_the_slack() -> None:
    assert read_in_range(-0.5, 0, 360, 0.5) == 0.0
    assert read_in_range(360.5, 0, 360, 0.5) == 360.0
    assert read_in_range(123.4, 0, 360, 0.5) == 123.4
    assert read_in_range(-0.6, 0, 360, 0.5) is None
    assert read_in_range(360.6, 0, 360, 0.5) is None
    assert read_in_range(453, 0, 450, 3) == 450.0 and read_in_range(454, 0, 450, 3) is None
