"""Review 125: review 118's fix (98de0667: a torn answer measured against the shortest reply,
``ModelSpec.least_reply_bytes``) takes Easycomm's shortest reply as ``AZ0.0 EL0.0`` LF, 12
bytes. An Easycomm box that reports whole degrees (``AZ150 EL0`` LF, 10 bytes; the protocol
makes decimals optional, protocols/easycomm.py, and the emulator's ``decimals=0`` builds it)
read at half rate (review 118's ``at_half_rate``: a box at twice the configured baud rate)
reaches the host as 5 bytes an answer, 10 over a run of two, under the 12 the fix asks: no
answer is ever counted torn, and the turn under way at the start runs to its end at 5, 55
degrees past az_min_deg 60, never stopped (the one-decimal box: stopped at 126). Easycomm III
and the azimuth-only build (``AZ150`` LF) the same. Not a regression (at 51a2f016 no half-rate
Easycomm was stopped); the fix misses the whole-degree form.

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
        "review 125: an Easycomm box reporting whole degrees, read at half rate, turning at "
        "the start runs past az_min_deg to its end, never stopped"
    ),
)
@pytest.mark.parametrize(
    ("model", "target"),
    [
        ("easycomm2", b"AZ5.0 EL0.0\n"),
        ("easycomm3", b"AZ5.0 EL0.0\n"),
        ("easycomm2-az", b"AZ5.0\n"),
    ],
)
def test_a_whole_degree_turn_read_at_half_rate_is_stopped_before_the_limit(
    rig: Rig, model: str, target: bytes
) -> None:
    v = turning_at_the_start(rig, model, target, {"decimals": 0})
    stopped_before_the_limit(v, at_half_rate())
