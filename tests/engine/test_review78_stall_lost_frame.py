"""Review 78 of motion.py rule 3's per-axis stall (0d308f96): an axis whose own frame was lost
on the line while it turned is called stalled, and the other axis's healthy turn stopped,
where controller.py rule 11 would have sent the target again.

An RC2800 az/el (a frame per axis) turning to azimuth 100, elevation 170, is sent azimuth 200,
elevation 175 five seconds in; the ``A200.0`` frame is lost on the line, ``E175.0`` arrives.
The azimuth, mid-turn when the target went, goes on to 100 and rests there; rule 11 judges
such an axis by where it rests, once the rotor has come to rest (``_left_behind``: no movement
of either axis for ``settle_s``), and the elevation still climbs for 30 s more. Judged on its
own, the azimuth is called stalled 10 s after it reached 100: the elevation is stopped at 83
on its way to 175, "rotor stalled at 100° ... brake paddle pressed, rotor stuck" is said and
rotor health counts a stall, for one frame lost on the line. 434064a6 (the shared progress)
let the elevation arrive, then sent the target again, and the rotor reached (200, 175). The
same on a Combi-Track (unit A's frame lost) and on a GS-232B (its one ``W`` frame lost: both
axes go on to the old target, the azimuth rests first). In virtual time
(tests/engine/virtual.py), the emulator's fast speeds."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind, MotionState
from tests.engine.virtual import VirtualRotator, settled_at

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0, "start_az_deg": 0, "start_el_deg": 0}
MID_TURN_S = 5.0  # the new target goes this long into the first turn


def test_a_lost_azimuth_frame_mid_turn_is_sent_again_not_called_a_stall(rig: Rig) -> None:
    v = rig("rc2800", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    t0 = v.now
    v.target(100, 170)
    v.run_for(MID_TURN_S)
    assert v.truth().is_moving and v.truth().az_deg < 100
    v.drop_writes(b"A200.0\r")  # (one frame lost on the line)
    v.target(200, 175)
    v.run_until(lambda h: settled_at(200, 175)(h) or h.state is MotionState.STALLED, 180, "an end")
    assert [w.data for w in v.writes if w.lost] == [b"A200.0\r"]
    said = [r.message for r in v.errors(ErrorKind.STALLED, since=t0)]
    assert said == [], said
    assert (v.truth().az_deg, v.truth().el_deg) == (200.0, 175.0)
    health = v.status.health
    assert health is not None and health.stalls == 0


def test_a_combi_tracks_lost_azimuth_frame_mid_turn_is_no_stall(rig: Rig) -> None:
    """The same on a Prosistel Combi-Track, whose units go a frame each (its elevation at 2
    degrees a second, set so, climbs 30 s after its azimuth rests): 434064a6 sent the target
    again once the rotor rested and reached (200, 88)."""
    v = rig(
        "prosistel-combi",
        settings={"el_speed_deg_s": 2.0},
        emulator={"start_az_deg": 0, "start_el_deg": 0, "el_speed_deg_s": 2.0},
    )
    v.run_until_state(MotionState.IDLE, 30)
    t0 = v.now
    v.target(100, 85)
    v.run_for(MID_TURN_S)
    v.drop_writes(b"\x02AG2000\r")  # (unit A's frame, lost on the line)
    v.target(200, 88)
    v.run_until(lambda h: settled_at(200, 88)(h) or h.state is MotionState.STALLED, 180, "an end")
    assert [w.data for w in v.writes if w.lost] == [b"\x02AG2000\r"]
    said = [r.message for r in v.errors(ErrorKind.STALLED, since=t0)]
    assert said == [], said
    assert (v.truth().az_deg, v.truth().el_deg) == (200.0, 88.0)


def test_a_gs232bs_lost_target_mid_turn_is_sent_again_not_called_a_stall(rig: Rig) -> None:
    """Not the two-frame boxes' alone: a GS-232B turning to (100, 80), its ``W200 085`` lost
    5 s in, goes on to the old target; its azimuth rests at 100 while the elevation climbs to
    80 for 15 s more (2.5 degrees a second). 434064a6 sent the target again once the rotor
    rested and reached (200, 85)."""
    v = rig("gs232b", emulator={"start_az_deg": 0, "start_el_deg": 0})
    v.run_until_state(MotionState.IDLE, 30)
    t0 = v.now
    v.target(100, 80)
    v.run_for(MID_TURN_S)
    v.drop_writes(b"W200 085\r")  # (the target's one frame, lost on the line)
    v.target(200, 85)
    v.run_until(lambda h: settled_at(200, 85)(h) or h.state is MotionState.STALLED, 180, "an end")
    assert [w.data for w in v.writes if w.lost] == [b"W200 085\r"]
    said = [r.message for r in v.errors(ErrorKind.STALLED, since=t0)]
    assert said == [], said
    assert (v.truth().az_deg, v.truth().el_deg) == (200.0, 85.0)


STALL_S = 10.0  # the bridge's default stall_timeout_s
POLL_MARGIN_S = 2.0  # a moving poll or two for the reading that tells it (not a deadline)


def test_an_azimuth_jammed_where_its_lost_frame_left_it_is_stopped_a_stall_timeout_after_the_try(
    rig: Rig,
) -> None:
    """The fix's other side: the axis left behind is sent the target once more as soon as it
    rests, and if it is really held there (jammed at the old target), the try does not move it
    and it is called stalled ``stall_timeout_s`` after that try (controller.py rule 11), the
    elevation's turn stopped with it, the error naming the azimuth."""
    v = rig("rc2800", emulator=FAST)
    assert v.cfg.motion.stall_timeout_s == STALL_S
    v.run_until_state(MotionState.IDLE, 30)
    t0 = v.now
    v.target(100, 170)
    v.run_for(MID_TURN_S)
    v.drop_writes(b"A200.0\r")
    v.target(200, 175)
    v.run_until(lambda h: h.truth().az_deg == 100.0, 60, "the azimuth at the old target")
    v.device._az.jam(v.now)  # type: ignore[attr-defined]  # held where the old turn left it
    v.run_until(lambda h: h.state is MotionState.STALLED, 60, "a stall")
    v.run_for(POLL_MARGIN_S)  # the stop the stall sends goes out
    tries = [w.t for w in v.writes if w.data == b"A200.0\r"]
    assert len(tries) == 2 and [w.lost for w in v.writes if w.data == b"A200.0\r"] == [
        True,
        False,
    ], tries
    stops = [w.t for w in v.writes if w.t > tries[-1] and w.data.endswith(b"S\r")]
    assert stops, "the jammed azimuth was never stopped"
    assert stops[0] <= tries[-1] + STALL_S + POLL_MARGIN_S, (stops[0] - tries[-1], tries)
    said = [r.message for r in v.errors(ErrorKind.STALLED, since=t0)]
    assert len(said) == 1 and said[0].startswith("rotor stalled at 100°"), said
    assert v.truth().az_deg == 100.0 and v.truth().el_deg < 170.0  # (stopped on its way)
    assert not v.truth().is_moving
