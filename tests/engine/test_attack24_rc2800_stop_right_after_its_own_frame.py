"""Attack 24: since 879598fc an RC2800's stop begins with the axis whose motor runs "by the last
reading" (rc2800.py rule 9), the azimuth where both or neither do. The last reading of an axis
is its last answered line, which says nothing of a frame the bridge itself wrote since: an
azimuth target written while the elevation turns starts the azimuth motor at once, but the
azimuth's last line (a poll from before, ``ST``) still says stopped until that axis is polled
again. A STOP in that window (here up to ~30 ms after the ``A200`` frame: the operator sends a
new bearing while the dish is still elevating, and stops it at once) is begun with the
elevation: ``E`` CR ``S`` CR the box's 200 ms gap after the ``A`` frame, and the azimuth's own
``A`` CR ``S`` CR a second gap later, 0.4 s after the STOP, where the azimuth's stop needed no
wait at all (the line's last frame was the azimuth's). The azimuth, the axis just set turning,
coasts about 2.4 degrees more at 6 degrees a second. 879598fc^ wrote ``A`` CR ``S`` CR at once
(the control below, 40 ms later, shows the same code stopping it at once once the azimuth's
next line said ``MV``). The same at rest, where 879598fc^ did no better: an elevation alone
written (``E60``), neither axis's last line ``MV``, a STOP 10 ms later begins with the idle
azimuth, its ``A`` CR ``S`` CR the gap after the ``E`` frame, and the elevation's own stop, which
could have gone at once, comes 0.4 s after the STOP (1.2 degrees more at 3 degrees a second).
One cause: the bridge knows which axis it has just set turning, and the order asks only the
readings.

Fixed (rule 9 now): an axis a drive frame went to since its last line counts as running, the
most recent such frame first, until a line the box said after that frame; the order with no
such frame is as before (the last two tests). In virtual time (tests/engine/virtual.py), an
RC2800 az/el at the emulator's fast speeds."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
SLACK_S = 0.02  # a few byte times at 9600 baud
RUN_ON_DEG = 0.3  # the azimuth's coast at 6 degrees a second if its stop goes at once
AXIS_GAP_S = 0.2  # the box's time between its two axes (rc2800.py rule 5)
READ_AGAIN_S = 1.0  # virtual time: each axis polled again at the moving rate, and answered


def stop_after_an_azimuth_frame(
    rig: Rig, after_s: float
) -> tuple[list[tuple[float, bytes]], float]:
    """The elevation turning, a new azimuth (200) sent, the STOP ``after_s`` after its ``A200``
    frame went: the frames from the STOP on (time after it, bytes) and the azimuth's coast."""
    v = rig("rc2800", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(None, 80)  # the dish elevates; the azimuth rests at 0
    v.run_until(lambda h: h.truth().is_moving and h.truth().el_deg > 10, 60, "elevating")
    sent_t = v.now
    v.target(200, None)  # a new bearing while it elevates
    v.run_until(
        lambda h: any(b"A200" in w.data for w in h.writes if w.t >= sent_t), 5, "A200 written"
    )
    v.run_for(after_s)
    assert v.truth().is_moving
    stop_t, az_at_stop = v.now, v.truth().az_deg
    v.stop()
    v.run_until(lambda h: not h.truth().is_moving, 10, "stopped")
    frames = [(round(w.t - stop_t, 3), w.data) for w in v.writes if w.t >= stop_t]
    assert v.truth().too_soon == 0  # the box's axis gap kept either way
    return frames, abs(v.truth().az_deg - az_at_stop)


def azimuth_stop_s(frames: list[tuple[float, bytes]]) -> float:
    return next(t for t, data in frames if b"A\rS\r" in data)


def test_control_a_stop_once_the_azimuths_next_line_said_it_runs_stops_it_at_once(
    rig: Rig,
) -> None:
    frames, coast_deg = stop_after_an_azimuth_frame(rig, 0.04)
    assert azimuth_stop_s(frames) <= SLACK_S, frames
    assert coast_deg < RUN_ON_DEG


def test_a_stop_right_after_an_azimuth_frame_stops_the_azimuth_at_once(rig: Rig) -> None:
    frames, coast_deg = stop_after_an_azimuth_frame(rig, 0.01)
    assert azimuth_stop_s(frames) <= SLACK_S, frames
    assert coast_deg < RUN_ON_DEG, f"azimuth coasted {coast_deg:.2f} degrees: {frames}"


def test_a_polls_answer_that_comes_after_an_azimuth_frame_does_not_end_it(rig: Rig) -> None:
    """The new azimuth written right behind an ``A`` CR poll (the axis last addressed: no
    wait), the poll's answer (``ST``, said before the frame reached the box) comes ~23 ms
    after the ``A200`` frame, the frame's own answer ~20 ms later: a STOP between the two
    still stops the azimuth at once, the line the poll owed saying nothing of the frame."""
    v = rig("rc2800", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(None, 80)
    v.run_until(lambda h: h.truth().is_moving and h.truth().el_deg > 10, 60, "elevating")
    v.run_until(lambda h: h.writes[-1].data == b"A\r" and h.writes[-1].t == h.now, 5, "A asked")
    v.target(200, None)
    sent_t = v.now
    assert [w.data for w in v.writes if w.t >= sent_t] == [b"A\r", b"A200.0\r"]
    v.run_until(lambda h: b"ST\r" in b"".join(d for t, d in h.received if t >= sent_t), 5, "ST")
    v.run_for(SLACK_S / 4)  # (the frame's own answer not whole yet)
    assert b"\r" not in b"".join(d for t, d in v.received if t >= sent_t).split(b"ST\r", 1)[1]
    stop_t, az_at_stop = v.now, v.truth().az_deg
    v.stop()
    v.run_until(lambda h: not h.truth().is_moving, 10, "stopped")
    frames = [(round(w.t - stop_t, 3), w.data) for w in v.writes if w.t >= stop_t]
    assert azimuth_stop_s(frames) <= SLACK_S, frames
    assert abs(v.truth().az_deg - az_at_stop) < RUN_ON_DEG
    assert v.truth().too_soon == 0


def stop_after_an_elevation_frame(rig: Rig) -> tuple[list[tuple[float, bytes]], float]:
    """The same at rest: a new elevation (60) alone, the STOP 10 ms after its ``E60`` frame
    went (neither axis's last line says ``MV``): the frames from the STOP on and the
    elevation's coast."""
    v = rig("rc2800", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(100, 10)
    v.run_until(lambda h: h.state is MotionState.IDLE and not h.truth().is_moving, 60, "at rest")
    sent_t = v.now
    v.target(None, 60)
    v.run_until(
        lambda h: any(b"E60" in w.data for w in h.writes if w.t >= sent_t), 5, "E60 written"
    )
    v.run_for(0.01)
    assert v.truth().is_moving
    stop_t, el_at_stop = v.now, v.truth().el_deg
    v.stop()
    v.run_until(lambda h: not h.truth().is_moving, 10, "stopped")
    frames = [(round(w.t - stop_t, 3), w.data) for w in v.writes if w.t >= stop_t]
    assert v.truth().too_soon == 0
    el_now = v.truth().el_deg
    assert el_now is not None and el_at_stop is not None
    return frames, abs(el_now - el_at_stop)


def test_a_stop_right_after_an_elevation_frame_stops_the_elevation_at_once(rig: Rig) -> None:
    frames, coast_deg = stop_after_an_elevation_frame(rig)
    el_stop_s = next(t for t, data in frames if b"E\rS\r" in data)
    assert el_stop_s <= SLACK_S, frames
    assert coast_deg < RUN_ON_DEG / 2, f"elevation coasted {coast_deg:.2f} degrees: {frames}"


def drive_frames(frames: list[bytes]) -> list[bytes]:
    return [f for f in frames if f[:1] in (b"A", b"E") and f[1:2].isdigit()]


def test_a_stop_with_no_drive_frame_since_the_readings_goes_by_them(rig: Rig) -> None:
    """A drive frame counts only until the box's next line of that axis: a new azimuth (30)
    written while the dish elevates, the last drive frame on the line, the azimuth arrived and
    read stopped since, the STOP begins with the elevation still turning (its ``E`` CR ``S``
    CR the gap after the last ``A`` CR poll) and the arrived azimuth's stop goes after it;
    were the ``A30`` frame still counted, the azimuth would go first and the elevation's stop
    a gap later."""
    v = rig("rc2800", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(None, 80)
    v.run_until(lambda h: h.truth().is_moving and h.truth().el_deg > 10, 60, "elevating")
    v.target(30, None)
    v.run_until(lambda h: abs(h.truth().az_deg - 30) < 0.05, 60, "the azimuth at 30")
    v.run_for(READ_AGAIN_S)  # its polls answered: the azimuth stopped, the elevation runs
    assert drive_frames([w.data for w in v.writes])[-1] == b"A30.0\r"
    el_now = v.truth().el_deg
    assert v.truth().is_moving and el_now is not None and el_now < 70
    stop_t = v.now
    v.stop()
    v.run_until(lambda h: not h.truth().is_moving, 10, "stopped")
    v.run_for(READ_AGAIN_S)  # the azimuth's stop too
    stops = [(w.t - stop_t, w.data) for w in v.writes if w.t >= stop_t and w.data.endswith(b"S\r")]
    assert [data for _, data in stops] == [b"E\rS\r", b"A\rS\r"], stops
    assert stops[0][0] <= AXIS_GAP_S + SLACK_S, stops


def test_a_stop_at_rest_long_after_its_frames_begins_with_the_azimuth(rig: Rig) -> None:
    """At rest, neither axis driven since its last line (a new elevation, ``E20`` the last
    frame written, its turn over and read): the STOP begins with the azimuth, as before
    attack 24's fix; were the ``E20`` frame still counted, the elevation would go first."""
    v = rig("rc2800", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(100, 10)
    v.run_until(lambda h: h.state is MotionState.IDLE and not h.truth().is_moving, 60, "at rest")
    v.run_until(lambda h: h.writes[-1].data == b"A\r", 5, "an azimuth poll")
    v.target(None, 20)  # its frames: the azimuth's (100, held) first, the elevation's last
    v.run_until(lambda h: h.truth().is_moving, 5, "elevating")
    v.run_until(lambda h: h.state is MotionState.IDLE and not h.truth().is_moving, 60, "at rest")
    v.run_for(READ_AGAIN_S)
    assert drive_frames([w.data for w in v.writes])[-1] == b"E20.0\r"
    stop_t = v.now
    v.stop()
    v.run_for(READ_AGAIN_S)
    stops = [w.data for w in v.writes if w.t >= stop_t and w.data.endswith(b"S\r")]
    assert stops == [b"A\rS\r", b"E\rS\r"], stops
