"""A turn the bridge watched, then a line gone bad on an adapter that resets every ``up_s``
(review 125): when its first stop frame went."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.garblers import STEP_S as LOWEST_STEP_S
from tests.engine.garblers import Garble
from tests.engine.virtual import VirtualRotator

START_DEG = 20.0
TARGET_DEG = 300.0
SETTLE_S = 60  # for the first readings to be taken, at rest (virtual time)
TURNING_S = 5.0  # the turn well under way, watched (virtual time, not a deadline)
WATCH_S = 30.0  # the silence, the offline and what follows (virtual time)
STEP_S = 0.05  # a step of virtual time to see the first stop: not a deadline
DOWN_S = 0.5  # the worker's reconnect_min_s: the port reopened this much later (virtual time)


def turning_watched(v: VirtualRotator) -> float:
    """``v`` settled at rest, then turning from START_DEG to TARGET_DEG for TURNING_S, watched
    (virtual time): when the turn was well under way (reviews 118 and 125)."""
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.target(TARGET_DEG)
    v.run_for(TURNING_S)
    assert v.truth().is_moving
    return v.now


def goes_bad(v: VirtualRotator, garble: Garble | None) -> None:
    """``v``'s line from now on: every byte through ``garble``, or silent if None."""
    if garble is None:
        v.set_silent(True)
    else:
        v.to_host = garble


def first_stop_s(v: VirtualRotator, garble: Garble | None, up_s: float | None) -> float | None:
    """``v`` settles, turns from START_DEG to TARGET_DEG for TURNING_S, then its line goes bad
    (every byte through ``garble``, or silent if None) and, if ``up_s``, the port fails every
    ``up_s`` and reopens DOWN_S later: how long after the line went bad the first stop frame
    went (None: none in WATCH_S)."""
    t = turning_watched(v)
    goes_bad(v, garble)
    drop_t = v.now + up_s if up_s else float("inf")
    while v.now < t + WATCH_S:
        v.run_for(STEP_S)
        if v.frames("stop", since=t):
            return v.now - t
        if v.now >= drop_t:
            v.link_down("adapter reset")
            v.run_for(DOWN_S)
            v.link_up()
            drop_t = v.now + (up_s or 0.0)
    return None


def lowest_az_resetting(v: VirtualRotator, until: float, start: float, up_s: float) -> float:
    """The lowest azimuth the rotor truly reached, from ``start``, stepping virtual time by
    garblers' STEP_S until ``until``, the port failing every ``up_s`` and reopened DOWN_S
    later (reviews 118 and 125)."""
    lowest, drop_t = start, v.now + up_s
    while v.now < until:
        v.run_for(LOWEST_STEP_S)
        lowest = min(lowest, v.truth().az_deg)
        if v.now >= drop_t:
            v.link_down("adapter reset")
            v.run_for(DOWN_S)
            v.link_up()
            drop_t = v.now + up_s
    return lowest


def alone_then_resetting(
    rig: Callable[..., VirtualRotator], model: str, garble: Garble | None, up_s: float
) -> tuple[VirtualRotator, float, float | None, float]:
    """``first_stop_s`` for a ``model`` box from START_DEG on one connection (it must stop),
    then on a fresh one whose adapter resets every ``up_s``: that rotor, the first stop on one
    connection, the first on the resetting one, and when that one was due at the latest (one
    reconnect's time on top)."""
    alone_s = first_stop_s(rig(model, emulator={"start_az_deg": START_DEG}), garble, None)
    assert alone_s is not None  # (one connection: stopped at the silence time)
    v = rig(model, emulator={"start_az_deg": START_DEG})
    stop_s = first_stop_s(v, garble, up_s)
    due_s = alone_s + DOWN_S + STEP_S  # (one reconnect's time at most on top)
    return v, alone_s, stop_s, due_s
