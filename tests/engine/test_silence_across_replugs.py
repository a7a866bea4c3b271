"""A silence goes on across a replug (link.py rule 2, controller.py rule 2; review 125): an
adapter that resets every 1.5 s (the rotor motor's interference on the cable, review 118) made
each connection shorter than the 3 s silence time, and a controller that gave nothing was
never told silent. In virtual time: the emulated GS-232B at rest, then silent, its port
failing every UP_S and reopened DOWN_S later (the worker's reconnect_min_s)."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
SETTLE_S = 60  # for the first readings to be taken, at rest (virtual time)
UP_S = 1.5  # the adapter resets this often (virtual time)
DOWN_S = 0.5  # and is back this much later
WATCH_S = 20.0  # a dozen replugs (virtual time)
STEP_S = 0.05  # a step of virtual time: not a deadline


def silent_on_a_resetting_adapter(v: VirtualRotator) -> float:
    """``v`` at rest, then silent, its adapter resetting every UP_S for WATCH_S: when it
    went silent (virtual time)."""
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    t = v.now
    v.set_silent(True)
    drop_t = v.now + UP_S
    while v.now < t + WATCH_S:
        v.run_for(STEP_S)
        if v.now >= drop_t:
            v.link_down("adapter reset")
            v.run_for(DOWN_S)
            v.link_up()
            drop_t = v.now + UP_S
    return t


def test_a_silent_controller_on_a_resetting_adapter_is_said_silent_once(rig: Rig) -> None:
    v = rig("gs232b", emulator={"start_az_deg": 150.0})
    t = silent_on_a_resetting_adapter(v)
    said = [(at - t, r.message) for at, r in v.events if at >= t and "answer" in r.message]
    assert len(said) == 1, said  # (once, not at each replug)
    at_s, why = said[0]
    assert "does not answer" in why
    # the silence time and the time the port was closed in it (nothing could be asked then),
    # and one reply time for the question that decides
    assert 3.0 <= at_s <= 3.0 + 2 * DOWN_S + 1.0 + STEP_S, said
    assert not v.frames("stop", since=t)  # (at rest: nothing to stop)
