"""Review 98: a composite's az/el azimuth box's own elevation is never turned nor read
(axes.py rule 1), so what it says there spoils nothing of the azimuth in the same reply
(base.py rule 10, ScalesElevation), in every codec that judges an elevation's range: GS-232 A
and B, Easycomm, RC2800, Combi-Track. Before, past base.py rule 10's slack, the whole reply was
spoiled ("position out of range"), and the rotator went offline for good.

Each case: the reply with that elevation past its slack, what the azimuth box reads of it, and
the target frames that box then writes for an azimuth of 130: its elevation sent back within
its own range (axes.py rule 1), never beyond it.
"""

from __future__ import annotations

import pytest

from bridge.protocols import REGISTRY
from bridge.protocols.axes import Axis, AzimuthOfAzEl, axis_spec
from bridge.protocols.base import JunkReason, JunkReply, PositionReply
from tests.support import HOW, feed

# model, a reply whose elevation is past the slack, the azimuth read, the target's frames
CASES = [
    ("gs232b", b"AZ=120  EL=190\r\n", 120.0, [b"W130 180\r"]),
    ("gs232b", b"AZ=120  EL=999\r\n", 120.0, [b"W130 180\r"]),
    ("gs232a", b"+0120+0190\r\n", 120.0, [b"W130 180\r"]),
    ("easycomm3", b"AZ120.0 EL181.0\n", 120.0, [b"AZ130.0 EL180.0\n"]),
    ("easycomm2", b"AZ120.0 EL-95.0\n", 120.0, [b"AZ130.0 EL0.0\n"]),
    ("rc2800", b"A P= 120.0 S=9 ST\rE P= 181.0 S=9 ST\r", 120.0, [b"A130.0\r", b"E180.0\r"]),
    ("rc2800", b"A P= 120.0 S=9 ST\rE P= -95.0 S=9 ST\r", 120.0, [b"A130.0\r", b"E0.0\r"]),
    (
        "prosistel-combi",
        b"\x02A,?,1200,B\r\x02B,?,0950,B\r",
        120.0,
        [b"\x02AG1300\r", b"\x02BG900\r"],
    ),
]


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize(("model", "reply", "az", "frames"), CASES)
def test_an_azimuth_boxs_own_elevation_past_its_slack_spoils_nothing_of_its_azimuth(
    how: str, model: str, reply: bytes, az: float, frames: list[bytes]
) -> None:
    codec = axis_spec(REGISTRY[model], Axis.AZIMUTH).codec_factory()
    assert isinstance(codec, AzimuthOfAzEl)
    for _ in range(2):  # axes.py rule 5: the elevation kept once two readings say it
        codec.encode_query()
        replies = feed(codec, reply, how)
        spoiled = [
            r for r in replies if isinstance(r, JunkReply) and r.reason is not JunkReason.CHATTER
        ]
        assert spoiled == [], replies
        readings = [r for r in replies if isinstance(r, PositionReply)]
        assert [(r.az_deg, r.el_deg) for r in readings] == [(az, None)], replies
        codec.taken(readings[0])
    assert codec.encode_target(130.0, None) == frames


@pytest.mark.parametrize(("model", "reply"), [(model, reply) for model, reply, _, _ in CASES])
def test_the_same_reply_to_the_box_configured_on_its_own_is_spoiled_as_ever(
    model: str, reply: bytes
) -> None:
    """base.py rule 10: an az/el box's elevation is judged as ever where it is the antenna's."""
    codec = REGISTRY[model].codec_factory()
    codec.encode_query()
    replies = codec.feed(reply)
    assert not [r for r in replies if isinstance(r, PositionReply)], replies
    assert [r for r in replies if isinstance(r, JunkReply) and r.reason is JunkReason.SPOILED]


@pytest.mark.parametrize(
    ("model", "reply"),
    [
        ("gs232b", b"AZ=460  EL=190\r\n"),
        ("easycomm3", b"AZ361.0 EL181.0\n"),
        ("rc2800", b"A P= 361.0 S=9 ST\rE P= 181.0 S=9 ST\r"),
        ("prosistel-combi", b"\x02A,?,3610,B\r\x02B,?,0950,B\r"),
    ],
)
def test_an_azimuth_boxs_own_azimuth_past_its_slack_is_spoiled_as_ever(
    model: str, reply: bytes
) -> None:
    """base.py rule 10: the axis the box turns is judged as ever (only the unused one is not)."""
    codec = axis_spec(REGISTRY[model], Axis.AZIMUTH).codec_factory()
    codec.encode_query()
    replies = codec.feed(reply)
    assert not [r for r in replies if isinstance(r, PositionReply)], replies
    assert [r for r in replies if isinstance(r, JunkReply) and r.reason is JunkReason.SPOILED]
