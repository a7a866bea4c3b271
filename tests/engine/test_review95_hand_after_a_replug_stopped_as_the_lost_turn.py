"""Found fixing review 95 (motion.py rule 2: a carried turn rests by each axis's own time):
controller.py rule 13 judges a turn the port dropped at "the first rest the readings show after
the port is back", and stops it with a ``stop`` error if that rest is short of its aim. A
GS-232B az/el whose turn to elevation 30 ended at its aim while the adapter was out: readings
back show the azimuth still for its own time (motion.py rule 4 decides it, ``still_axes``), so a
hand at the azimuth after that is a turn begun since, not the lost one (``lost_still``). Yet
the first rest after the port came back is the hand's, at 182, and rule 13 took it for the lost
turn's: a stop to the rotor at rest and R/error "rotor at rest at 182° since its port came back,
short of its turn to 62°, elevation 30° ... (jammed, stopped at the panel, or its power cut
meanwhile)", none of which happened. Before the per-axis rest this showed for a hand begun up to
1.2 s after the port answered (the carried turn called at rest at settle_s, 1.5 s, at its aim,
ended rule 13 unsaid after that); with it, up to 2.1 s (the elevation's own time)."""

from __future__ import annotations

from bridge.core.model import ErrorKind, MotionState
from bridge.session import motion as mo
from tests.engine.virtual import VirtualRotator

SWEEP_STEP_S = 0.05  # a quarter of the GS-232B's moving poll: every reading's phase is met


def stops_for_a_hand_after_a_replug(hand_after_s: float) -> tuple[list[str], int]:
    """The ``stop`` errors and the stop frames from the hand's start on."""
    with VirtualRotator("gs232b", emulator={"start_az_deg": 62, "start_el_deg": 0}) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "at rest")
        v.target(62, 30.0)
        v.run_until(lambda h: h.truth().el_deg >= 25.0, 60, "the elevation turning")
        v.run_for(0.1)  # (between two polls: not a deadline)
        v.link_down()
        v.run_for(4.0)  # (the adapter out while the turn ends at its aim: not a deadline)
        assert not v.truth().is_moving and v.truth().el_deg == 30.0
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers again")
        v.run_for(hand_after_s)  # (not a deadline)
        hand_t = v.now
        v.manual_rotate(182)  # a hand at the panel
        v.run_until(lambda h: not h.truth().is_moving and h.truth().az_deg > 180, 90, "turned")
        v.run_for(5.0)  # (its rest told: not a deadline)
        errors = [e.message for e in v.errors(ErrorKind.STOP, since=hand_t)]
        return errors, sum(f.outcome == "stop" for f in v.frames(since=hand_t))


def test_a_hand_at_an_axis_shown_still_after_a_replug_is_not_taken_for_the_lost_turn() -> None:
    with VirtualRotator("gs232b") as v:
        cfg = v.cfg.motion
    seen = mo.axis_seen_s(cfg)
    # from the azimuth's own time (decided still before the hand begins) to a settle_s past
    # the carried turn's rest, the slowest axis's own time
    first = int(seen["azimuth"] / SWEEP_STEP_S) + 1
    last = int((max(cfg.settle_s, mo.carried_seen_s(cfg)) + cfg.settle_s) / SWEEP_STEP_S) + 1
    stopped = {}
    for i in range(first, last):
        errors, frames = stops_for_a_hand_after_a_replug(i * SWEEP_STEP_S)
        if errors or frames:
            stopped[round(i * SWEEP_STEP_S, 2)] = (errors, frames)
    # observed before _lost_decided: a stop and "rotor at rest at 182° since its port came
    # back, short of its turn" for a hand begun 1.1-2.15 s after the port answered (every
    # start swept)
    assert stopped == {}


def test_a_hand_before_the_azimuth_is_shown_still_is_the_lost_turn_to_the_bridge() -> None:
    """The control: a hand begun at the port's answer is in the readings before they can tell
    it from the lost turn (rule 13: "the readings cannot tell which"); its rest short of the
    aim gets the stop and the error, as ever."""
    errors, frames = stops_for_a_hand_after_a_replug(0.0)
    assert frames >= 1 and len(errors) == 1 and "short of its turn" in errors[0]
