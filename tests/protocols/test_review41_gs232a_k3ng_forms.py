"""Review 41, GS-232A: K3NG's answer for an elevation a little below the horizon has exactly
two forms (gs232.py rule 2; k3ng_rotator_controller.ino, review 39's lines 17974-18023): ``-0``
and then the whole degrees zero-padded to three places, so ``-0000`` (-0.x) and ``-000-1`` ..
``-000-3``. The pattern that reads them (``_A_EL``: ``-0`` then the B form's ``0{0,2}-[1-3]``)
takes short forms no firmware sends, ``+0123-0-1`` and ``+0123-00-1``, as the horizon: a line
with bytes lost, or junk, read as a position, where rule 2 reads only this model's reply form
(three digits a value). Severity low: the value read is the horizon either way."""

from __future__ import annotations

import pytest

from bridge.protocols import REGISTRY
from bridge.protocols.base import PositionReply


@pytest.mark.parametrize("el", [b"-0-1", b"-00-1", b"-00-3", b"-0-3"])
def test_a_gs232a_elevation_below_the_horizon_in_no_k3ng_form_is_no_reading(el: bytes) -> None:
    codec = REGISTRY["gs232a"].codec_factory()
    codec.encode_query()
    replies = codec.feed(b"+0123" + el + b"\r\n")
    assert not [r for r in replies if isinstance(r, PositionReply)], replies
