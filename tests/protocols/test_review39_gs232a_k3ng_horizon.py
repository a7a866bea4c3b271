"""Review 39, GS-232A: K3NG's firmware in GS-232A emulation says an elevation a little below
the horizon with a minus sign (``+0123-0000``), and the bridge reads no position at all.

K3NG's rotator controller answers ``C2`` (k3ng_rotator_controller.ino at 3788ad5, lines
17974-18023): in GS-232A emulation (rotator_features.h line 117: comment out
``OPTION_GS_232B_EMULATION`` and the box speaks GS-232A, as ARS-USB and the older Windows
clients expect) the elevation's part starts ``-0`` when ``elevation < 0`` (line 18005), then the
whole degrees zero-padded to three places: a G-5500 whose pot reads -0.4 at the horizon answers
``+0123-0000``, one at -1.2 ``+0123-000-1``. The GS-232B form of the same thing, ``EL=00-1``,
is read as the horizon (gs232.py rule 2, "K3NG's form of an elevation 1 to 3 degrees below 0";
tests/protocols/test_gs232.py), and the protocol sheet (/work/shared/protocols/more-controllers.md,
GS-232 section) names K3NG among the GS-232 boxes; the GS-232A form is called "not a reply
line" (NOISE) every poll, so an az/el K3NG box parked at the horizon never gives a reading and
the rotator goes offline where it stands. (Hamlib's gs232a.c, line 203 at 4.5.4, ``sscanf(posbuf,
"+0%d+0%d", ...)``, does not read it either: K3NG's source is the authority here, as it is for
the B form.)
"""

from __future__ import annotations

import pytest

from bridge.protocols import REGISTRY
from bridge.protocols.base import PositionReply


@pytest.mark.parametrize("el", [b"-0000", b"-000-1", b"-000-3"])
def test_k3ng_gs232a_a_little_below_the_horizon_is_the_horizon(el: bytes) -> None:
    codec = REGISTRY["gs232a"].codec_factory()
    assert codec.encode_query() == b"C2\r"
    replies = codec.feed(b"+0123" + el + b"\r\n")
    readings = [(r.az_deg, r.el_deg) for r in replies if isinstance(r, PositionReply)]
    assert readings == [(123.0, 0.0)], replies


@pytest.mark.parametrize("el", [b"-000-4", b"-0123", b"-0001", b"+000-1"])
def test_gs232a_further_below_the_horizon_or_an_unknown_sign_form_is_no_reading(el: bytes) -> None:
    codec = REGISTRY["gs232a"].codec_factory()
    codec.encode_query()
    replies = codec.feed(b"+0123" + el + b"\r\n")
    assert not [r for r in replies if isinstance(r, PositionReply)], replies
