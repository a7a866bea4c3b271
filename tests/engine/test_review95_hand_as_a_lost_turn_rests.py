"""Review 95 (found attacking e0f93948; not new in it: the same with no start refused, and on
its parent): 03af385a was reverted because a hand at a GS-232's panel, begun while the bridge
still judged the turn, published one 'idle' status with the hand's new bearing before
'moving' (tests/engine/test_session_gs232.py: a hand at the panel is one move). The same shows
after a replug: a GS-232B az/el whose turn to elevation 30 ended while its adapter was out is
counted moving from the first reading back (motion.py rule 4); a hand at the azimuth some 1.1 s
on, its first readings within ``noise_deg`` of where the rotor stood (63, 64), is in the
readings when rule 2 calls the carried turn at rest (``settle_s`` after the first reading
back): R/status says 'moving' at 63, 'idle' at 64, then 'moving' at 65 as the hand turns on,
one hand's turn told as two moves (observed for a hand begun 1.07 to 1.19 s after the port
answered again).

The carried turn's rest by each axis's own time (motion.py rule 2, ``carried_rest_from``) only
moved that window with the rest, to a hand begun about 1.9 s after the port answered (the
elevation's own 2.1 s): the rest is called at a reading that shows the hand's first degrees,
inside ``noise_deg``. So the hand's start is swept across the whole time the carried turn is
judged, not pinned to one window."""

from __future__ import annotations

import itertools

from bridge.core.model import MotionState
from bridge.session import motion as mo
from tests.engine.virtual import VirtualRotator

#: after the port answers again, before the carried turn's rest by settle_s: the window was
#: 1.25-1.35 s (the connect's confirming answer, controller.py rule 9, moved it from 1.07-1.19 s)
HAND_AFTER_S = 1.3
SWEEP_STEP_S = 0.05  # a quarter of the GS-232B's moving poll: every reading's phase is met


def states_of_a_hand_after_a_replug(hand_after_s: float) -> list[MotionState]:
    """The states R/status shows from the first status with the hand's bearing, grouped."""
    with VirtualRotator("gs232b", emulator={"start_az_deg": 62, "start_el_deg": 0}) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "at rest")
        v.target(62, 30.0)
        v.run_until(lambda h: h.truth().el_deg >= 25.0, 60, "the elevation turning")
        v.run_for(0.1)  # (between two polls: not a deadline)
        v.link_down()
        v.run_for(4.0)  # (the adapter out while the turn ends: not a deadline)
        assert not v.truth().is_moving and v.truth().el_deg == 30.0
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers again")
        v.run_for(hand_after_s)  # (not a deadline)
        hand_t = v.now
        v.manual_rotate(182)  # a hand at the panel
        v.run_until(lambda h: not h.truth().is_moving and h.truth().az_deg > 180, 90, "turned")
        v.run_for(5.0)  # (its rest told: not a deadline)
        # from the first status that shows the hand's bearing
        shown = itertools.dropwhile(lambda s: s.bearing_deg == 62, v.published(since=hand_t))
        return [k for k, _ in itertools.groupby(s.state for s in shown)]


def test_a_hand_just_after_a_replug_is_one_move() -> None:
    # observed: [MOVING, IDLE, MOVING, IDLE] ('idle' at 64 while the hand turned on)
    assert states_of_a_hand_after_a_replug(HAND_AFTER_S) == [MotionState.MOVING, MotionState.IDLE]


def test_a_hand_after_a_replug_is_one_move_whenever_it_begins() -> None:
    with VirtualRotator("gs232b") as v:
        cfg = v.cfg.motion
    # every start until the carried turn's rest, the slowest axis's own time, and a settle_s on
    end_s = max(cfg.settle_s, mo.carried_seen_s(cfg)) + cfg.settle_s
    starts = [i * SWEEP_STEP_S for i in range(int(end_s / SWEEP_STEP_S) + 1)]
    twice = [
        s
        for s in starts
        if states_of_a_hand_after_a_replug(s) != [MotionState.MOVING, MotionState.IDLE]
    ]
    # observed before the creep counted (rule 2): a hand begun 1.85-1.95 s on
    assert twice == []
