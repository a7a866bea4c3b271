"""Review 49: gs232.py rule 2 (092c55df) tells an azimuth past a 360-degree model's scale on
R/error, as soon as it comes (controller.py rule 6), in words that say the box is set up as the
450-degree model: 'configure model = "gs232b-az-450", or set the box to 360 degrees (P36)'.
A box at P45 says so at every reply; one reply alone does not: on a noisy line a single
flipped bit (``AZ=030`` read as ``AZ=430``: '0' 0x30 and '4' 0x34 are one bit apart) at rest is
now told as a box set up otherwise, where before 092c55df rule 9 told it as what it is, "a
reading at rest of 430 ... was not said again: ignored (line noise?)". Likewise a failing
position sensor whose readings wander past 360 among others (the failing-sensor doubt tests'
cycle before 092c55df changed it to leave 450 out): the first words on R/error send the
operator to change the model, and "readings in a row at rest disagree ... a failing position
sensor" waits a whole junk_report_interval_s behind them. In virtual time, an emulated
GS-232B."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import Target
from bridge.session.motion import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def _at_rest(rig: Rig, model: str, az: float) -> VirtualRotator:
    v = rig(model, settings={"unasked_moves": "follow"})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.aim(Target(az, 0.0 if v.cfg.spec.has_elevation else None))
    v.run_until(lambda h: h.state is MotionState.IDLE and h.now > 10, 200, f"at {az:g}")
    v.run_for(10)
    assert v.status.bearing_deg == az
    return v


def test_one_flipped_bit_past_360_at_rest_is_told_as_line_noise_not_as_a_box_set_to_p45(
    rig: Rig,
) -> None:
    v = _at_rest(rig, "gs232b-az", 30.0)
    t = v.now
    v.read_once_as(b"A", b"AZ=430\r\n")  # the box's next reply, one bit flipped on the line
    v.run_for(40)
    assert v.status.bearing_deg == 30.0 and v.status.available
    told = [e.message for e in v.errors(since=t)]
    assert told, "a glitch at rest went unsaid"
    assert not any("P45" in m or "configure model" in m for m in told), told
    assert any("line noise" in m for m in told), told


def test_a_failing_sensor_wandering_past_360_is_told_as_a_failing_sensor_first(
    rig: Rig,
) -> None:
    v = _at_rest(rig, "gs232b", 150.0)
    digits = iter(b"2340" * 1000)  # 150 reads 250, 350, 450, 50, 250...
    v.to_host = lambda data, now: (
        data.replace(b"1", bytes([next(digits)])) if b"1" in data else data
    )
    t = v.now
    v.run_for(30)
    assert v.status.bearing_deg == 150.0 and v.status.available
    told = [e.message for e in v.errors(since=t)]
    assert told and "failing position sensor" in told[0], told
    assert not any("configure model" in m for m in told), told
