"""Review 78 of rc2800.py rule 9 (3094b57e): a stop begins with an axis that a drive frame went
to since its last line, the most recent such frame first, even where that axis's stop must
wait the box's 200 ms gap and the other axis, running by its own last line, could be stopped
at once (link.py rule 10: "a stop waits for nothing but that gap").

A box whose answers come a little late (``answer_after``: a serial server on the network, a
slow USB adapter; link.py rule 12 learns such a box) keeps the elevation's frame counted past
the next ``A`` CR poll: the azimuth turning to 200, a new elevation sent (its frames ``A200.0``,
held, then ``E60.0`` 200 ms later), the STOP as the poll after it goes out (``A`` CR, the
last frame written, the ``E60.0``'s answer still on its way). 3094b57e begins the stop with
the elevation: its ``E`` CR ``S`` CR the gap after that poll, and the turning azimuth's own
``A`` CR ``S`` CR a second gap later, 0.4 s after the STOP (2.4 degrees more at 6 degrees a
second). 434064a6 (by the lines: the azimuth's says ``MV``) wrote ``A`` CR ``S`` CR at once
and the elevation's at the same 0.2 s: the new order stops neither axis sooner and the azimuth
0.4 s later. A box answering on time does the same when one noise byte garbles the
``E60.0``'s answer (``E #=``, told as 18 bytes no valid reply): the frame stays counted until
the elevation's next line, past the next ``A`` CR poll. In virtual time
(tests/engine/virtual.py), the emulator's fast speeds."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
LATE_S = 0.25  # each answer starts this long after its frame (a serial server on the network)
SLACK_S = 0.02  # a few byte times at 9600 baud
RUN_ON_DEG = 0.3  # the azimuth's coast at 6 degrees a second if its stop goes at once


def stop_as_the_poll_after_an_elevation_frame_goes(
    rig: Rig, late_s: float, garbled: bool = False
) -> VirtualRotator:
    """The azimuth turning to 200, an elevation (60) sent, the rig run to the instant the
    ``A`` CR poll after its ``E60.0`` frame is written (``garbled``: the first ``P`` the box
    sends after that frame, its answer's, reaches the bridge as ``#``)."""
    v = rig("rc2800", emulator=FAST)
    if late_s:
        v.answer_after(late_s)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, None)
    v.run_until(lambda h: h.truth().is_moving and h.truth().az_deg > 30, 60, "turning")
    sent_t = v.now
    v.target(None, 60)
    v.run_until(lambda h: any(w.data == b"E60.0\r" for w in h.writes if w.t >= sent_t), 5, "E60")
    el_t = v.now
    if garbled:
        flipped: list[float] = []

        def garble(data: bytes, now: float) -> bytes:
            if flipped or data != b"P":
                return data
            flipped.append(now)
            return b"#"

        v.to_host = garble
    v.run_until(lambda h: h.writes[-1].data == b"A\r" and h.writes[-1].t == h.now, 5, "A asked")
    assert v.now > el_t
    return v


def azimuth_stop(v: VirtualRotator, stop_t: float) -> float:
    return next(w.t - stop_t for w in v.writes if w.t >= stop_t and w.data.endswith(b"A\rS\r"))


def test_control_a_box_on_time_has_its_turning_azimuth_stopped_at_once(rig: Rig) -> None:
    """The same with answers on time: the ``E60.0``'s answer came before the poll, the
    azimuth's stop goes at once."""
    v = stop_as_the_poll_after_an_elevation_frame_goes(rig, 0.0)
    stop_t, az_at_stop = v.now, v.truth().az_deg
    v.stop()
    v.run_until(lambda h: not h.truth().is_moving, 10, "stopped")
    assert azimuth_stop(v, stop_t) <= SLACK_S
    assert abs(v.truth().az_deg - az_at_stop) < RUN_ON_DEG
    assert v.truth().too_soon == 0


def test_a_late_box_has_its_turning_azimuth_stopped_at_once(rig: Rig) -> None:
    v = stop_as_the_poll_after_an_elevation_frame_goes(rig, LATE_S)
    el_sent_t = max(w.t for w in v.writes if w.data == b"E60.0\r")
    heard = b"".join(data for t, data in v.received if t >= el_sent_t)
    assert b"E P=" not in heard, heard  # (the elevation frame's answer is still on its way)
    stop_t, az_at_stop = v.now, v.truth().az_deg
    assert v.truth().is_moving
    v.stop()
    v.run_until(lambda h: not h.truth().is_moving, 10, "stopped")
    frames = [(round(w.t - stop_t, 3), w.data) for w in v.writes if w.t >= stop_t]
    assert v.truth().too_soon == 0  # (the box's gap kept either way)
    coast_deg = abs(v.truth().az_deg - az_at_stop)
    assert azimuth_stop(v, stop_t) <= SLACK_S, frames
    assert coast_deg < RUN_ON_DEG, f"azimuth coasted {coast_deg:.2f} degrees: {frames}"


def stop_and_measure(v: VirtualRotator) -> tuple[list[tuple[float, bytes]], float, float]:
    """The STOP now: the frames from it on, the azimuth stop's time after it and its coast."""
    stop_t, az_at_stop = v.now, v.truth().az_deg
    assert v.truth().is_moving
    v.stop()
    v.run_until(lambda h: not h.truth().is_moving, 10, "stopped")
    frames = [(round(w.t - stop_t, 3), w.data) for w in v.writes if w.t >= stop_t]
    assert v.truth().too_soon == 0  # (the box's gap kept either way)
    return frames, azimuth_stop(v, stop_t), abs(v.truth().az_deg - az_at_stop)


def test_a_garbled_elevation_answer_leaves_the_turning_azimuth_stopped_at_once(rig: Rig) -> None:
    v = stop_as_the_poll_after_an_elevation_frame_goes(rig, 0.0, garbled=True)
    assert [e for e in v.errors() if "no valid reply" in e.message]  # (the garbled line, told)
    frames, az_stop_s, coast_deg = stop_and_measure(v)
    assert az_stop_s <= SLACK_S, frames
    assert coast_deg < RUN_ON_DEG, f"azimuth coasted {coast_deg:.2f} degrees: {frames}"
