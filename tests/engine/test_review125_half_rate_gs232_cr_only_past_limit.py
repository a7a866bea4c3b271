"""Review 125: review 118's fix (98de0667: a torn answer measured against the shortest reply,
``ModelSpec.least_reply_bytes``, 0 for GS-232: its ``reply_bytes``) takes a GS-232 answer as
ending in CR LF. A box that ends its lines with CR alone (Green Heron's GS-232B mode, some
clones: tests' GS-232 emulator, ``line_ending``), or a GS-232B that puts one space between its
fields (``AZ=150 EL=000``), read at half rate (review 118's ``at_half_rate``: a box at twice
the configured baud rate) reaches the host a byte short of half its reply every other answer:
no run of two torn answers ever reaches the reply's bytes, none is counted, and the turn under
way at the start runs to its end at 5, 55 degrees past az_min_deg 60, never stopped (the same
boxes with CR LF: stopped at 98). Not a regression (51a2f016 stopped none of them).

In virtual time: review 113's start (the emulated box turning from 150 to 5 when the bridge
starts); every second byte it sends reaches the host, garbled.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import (
    at_half_rate,
    stopped_before_the_limit,
    turning_at_the_start,
)
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.xfail(
    strict=True,
    reason=(
        "review 125: a GS-232 box ending its lines in CR alone (or a GS-232B with one space), "
        "read at half rate, turning at the start runs past az_min_deg to its end"
    ),
)
@pytest.mark.parametrize(
    ("model", "line_ending", "spacing"),
    [
        ("gs232b", b"\r", 2),
        ("gs232a", b"\r", 2),
        ("gs232a-az", b"\r", 2),
        ("gs232b-az", b"\r", 2),
        ("gs232b", b"\r\n", 1),
    ],
)
def test_a_gs232_turn_read_at_half_rate_is_stopped_before_the_limit(
    rig: Rig, model: str, line_ending: bytes, spacing: int
) -> None:
    v = turning_at_the_start(
        rig, model, b"M005\r", {"line_ending": line_ending, "spacing": spacing}
    )
    stopped_before_the_limit(v, at_half_rate())
