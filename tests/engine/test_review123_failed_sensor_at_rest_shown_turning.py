"""Review 123: a Rotor-EZ at rest whose position sensor fails (each ``1`` it sends reads as the
next of ``2``, ``3``, ``4``, ``0``) is shown MOVING about 13 s on, its bearing published jumping
between 50, 250 and 354 while it stands at 150, stopped again every 2 s as "still turning after a
stop", and R/error says "rotor still turning after 3 stop commands; stop it at the controller":
the operator is sent to a box that is not turning. Regression of e1e5afb3 (review 116's second
fix: the next unwatched stop at rest by the clock); in its parent the same sensor is kept at
rest, the bearing shown the last two readings agreed on (150), and stopped as rule 9's unwatched
stop, said as "readings in a row at rest do not agree".

controller.py rule 9: readings at rest that go on disagreeing are doubted, "the bearing shown is
the last two readings agreed on", and get the unwatched stop; none is taken as where the rotor
is. Measured at e1e5afb3 and since: the failing answers come to be taken as a turn's (the motion
machine MOVING, no target), the stop's check reads the garbled values as the rotor still turning
(54 stops in two minutes, polled about 330 times a minute where the parent polled 73), and the
readings' count that brings the unwatched stop is no longer kept.

In virtual time: the emulated Rotor-EZ at rest at 150, confirmed on a clean line; then each ``1``
it sends reaches the host as the next of ``2``, ``3``, ``4``, ``0``, for a minute. A RotorCard
(the same family) the same.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.garblers import STEP_S
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
CONFIRMED_S = 15.0  # the start's readings on a clean line (virtual time, not a deadline)
FAILED_S = 60.0  # the sensor failed for a minute (virtual time)
STILL_TURNING = "still turning after"


def failing() -> Callable[[bytes, float], bytes]:
    digits = itertools.cycle(b"2340")

    def sensor(data: bytes, now: float) -> bytes:
        return bytes(next(digits) if b == ord("1") else b for b in data)

    return sensor


@pytest.mark.xfail(
    strict=True,
    reason="review 123: a Rotor-EZ at rest with a failed sensor is shown moving, its bearing "
    "jumping 50/250/354, and told 'still turning after 3 stop commands' (regression, e1e5afb3)",
)
@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_a_failed_sensor_at_rest_is_shown_at_rest_where_it_stood(rig: Rig, model: str) -> None:
    v = rig(model, emulator={"start_az_deg": REST_DEG}, connect=False)
    v.link_up()
    v.run_for(CONFIRMED_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG  # (confirmed, clean line)
    v.to_host = failing()
    t = v.now
    shown: set[tuple[MotionState, float | None]] = set()
    while v.now < t + FAILED_S:
        v.run_for(STEP_S)
        shown.add((v.status.state, v.status.bearing_deg))
    assert v.truth().az_deg == REST_DEG  # (the premise: nobody turned it)
    said = [e.message for e in v.errors(since=t)]
    assert any("readings in a row at rest do not agree" in s for s in said), said
    assert not [s for s in said if STILL_TURNING in s], said
    assert shown == {(MotionState.IDLE, REST_DEG)}, sorted(shown, key=str)[:8]
