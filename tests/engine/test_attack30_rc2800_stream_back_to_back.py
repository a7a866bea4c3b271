"""Attack 30: an RC2800 that streams its position lines back to back is taken for silent.

Some RC2800s send their position lines unasked, continuously (rc2800.py rules 1 and 2: "the
box's own stream", a well-formed line of every axis a reading; Hamlib's rc2800.c: "The
continuous output of some of the RC2800 models can be a nuisance"). A microcontroller that
prints continuously prints its lines back to back: at 9600 baud one line (``A P= 123.4 S=9
ST`` CR) is 18.75 ms on the wire. When the gap between lines is shorter than link.py rule 9's
quiet time (three byte times, 3.1 ms), no reading ever settles:

- ``rc2800-az`` streaming a line every 20 ms (1.25 ms apart): offline from the start, "does
  not answer", though the box says its position 50 times a second; no target ever goes;
- ``rc2800`` (az/el) streaming both axes every 40 ms (2.5 ms apart): a turn from 100 to 200 is
  called silent mid-turn ("stopped answering (no valid reply for 3 s) while the rotor turned
  to its target"), stopped at ~145 and its target dropped.

In virtual time, the emulated box's stream (``stream_s``: a line of each axis every that long,
sent as soon as the line is free).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.virtual import VirtualRotator

START_DEG = 100.0
TARGET_DEG = 200.0
TARGET_EL_DEG = 30.0
KEEPS_UP_DEG = 5.0  # a reading at the moving poll's rate is this close at 6 degrees a second
WATCH_S = 40  # the turn at 6 degrees a second, with room


@pytest.mark.xfail(
    strict=True,
    reason="attack 30: an RC2800 streaming its lines back to back is offline ('does not "
    "answer') or stopped mid-turn as silent ('stopped answering')",
)
@pytest.mark.parametrize(("model", "stream_s"), [("rc2800-az", 0.02), ("rc2800", 0.04)])
def test_an_rc2800_streaming_back_to_back_is_read_and_turned(
    rig: Callable[..., VirtualRotator], model: str, stream_s: float
) -> None:
    el = TARGET_EL_DEG if model == "rc2800" else None
    v = rig(model, emulator={"start_az_deg": START_DEG, "stream_s": stream_s})
    v.run_for(5)
    v.target(TARGET_DEG, el)
    behind: list[tuple[float, float | None, float]] = []
    for _ in range(WATCH_S):
        v.run_for(1.0)
        shown, truth = v.status.bearing_deg, v.truth().az_deg
        if shown is None or abs(shown - truth) > KEEPS_UP_DEG:
            behind.append((round(v.now), shown, round(truth, 1)))
    told = [e.message for e in v.errors()]
    assert v.truth().az_deg == TARGET_DEG, told
    assert v.status.available and v.status.bearing_deg == TARGET_DEG, told
    assert not behind, f"(time, shown, rotor) where the bearing shown was off: {behind}"
