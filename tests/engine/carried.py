"""Set-up shared by the carried-turn reviews (95, 101, 110): a virtual rotator brought to rest,
then its adapter pulled mid-turn and plugged back in, so that the turn goes on unasked across
the replug (motion.py rule 2's carried turn; controller.py's first readings after a replug).
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Garble = Callable[[bytes, float], bytes]

BETWEEN_POLLS_S = 0.1  # pulled between two polls
OUT_S = 2.0  # the adapter out
BRAKE_S = 6.0  # a GS-232's brake delay, with room


def at_rest(v: VirtualRotator) -> None:
    """``v`` answering, read at rest and its brake delay over (virtual time)."""
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
    v.run_for(BRAKE_S)  # (settled: not a deadline)


def replugged(v: VirtualRotator, out_s: float = OUT_S) -> None:
    """``v``'s adapter pulled between two polls, out ``out_s`` (virtual time), plugged back in,
    and the controller answering again; the rotor goes on with whatever it was doing."""
    v.run_for(BETWEEN_POLLS_S)  # (between two polls: not a deadline)
    v.link_down()
    v.run_for(out_s)  # (the adapter out: not a deadline)
    v.link_up()
    v.run_until(lambda h: h.status.available, 10, "the controller answers again")


def jammed_after_a_carried_turn(v: VirtualRotator, drift: Callable[[float], Garble]) -> float:
    """An RC2800 turning to 300 (from its start at rest), replugged, its carried turn followed,
    then jammed with its motor driving and its lines rewritten by ``drift(jam_t)``: the jam's
    time (reviews 110 and 115)."""
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.run_until(lambda h: h.state is MotionState.IDLE, 30, "at rest")
    v.target(300)
    v.run_until(lambda h: h.truth().az_deg >= 40.0, 60, "the azimuth turning")
    replugged(v)
    v.run_for(3.0)  # (the carried turn followed: not a deadline)
    assert v.truth().is_moving and v.status.moving
    jam_t = v.now
    v.jam()  # its motor driving
    v.to_host = drift(jam_t)
    return jam_t


def carried_azimuth_turn(v: VirtualRotator, el_aim: float | None) -> None:
    """``v`` at rest, sent to azimuth 250 (elevation ``el_aim``: nothing for it to do), its
    azimuth turning past 80, then replugged: the carried azimuth turn of the jam reviews
    (110, 115, 119) going on unasked."""
    at_rest(v)
    v.target(250, el_aim)  # nothing for the elevation to do
    v.run_until(lambda h: h.truth().az_deg >= 80.0, 60, "the azimuth turning")
    replugged(v)
