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

from tests.engine.test_review118_half_rate_garbled_start import at_half_rate
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 150.0
AZ_MIN_DEG = 60.0
TURNING_S = 0.5  # the turn under way when the bridge starts (virtual time, not a deadline)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)
STEP_S = 0.1  # a step of virtual time to see the lowest bearing: not a deadline


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
    v = rig(
        model,
        emulator={"start_az_deg": START_DEG, "line_ending": line_ending, "spacing": spacing},
        settings={"az_min_deg": AZ_MIN_DEG},
        connect=False,
    )
    v.device.receive(b"M005\r", v.now)  # (turning when the bridge starts)
    v.run_for(TURNING_S)
    assert v.truth().is_moving
    t = v.now
    v.to_host = at_half_rate()
    v.link_up()
    lowest = START_DEG
    while v.now < t + WATCH_S:
        v.run_for(STEP_S)
        lowest = min(lowest, v.truth().az_deg)
    said = [e.message for e in v.errors(since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {START_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stop frames: {len(v.frames('stop', since=t))}; said: {said}"
    )
