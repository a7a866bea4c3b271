"""Review 100: a connection's first reading of a rotor turning faster than its nominal speed is
never confirmed while it turns.

controller.py rule 9 (``_doubts_first``, commits a8a074df and 80801409) believes a connection's
first reading only when the next agrees within ``doubt_deg`` plus twice the nominal speed times
the time between them; after DOUBTS_TOLD readings in a row that disagree, within ``doubt_deg``
alone at the usual polls. A rotor turning when the bridge starts (a restart mid-turn, a hand at
the panel) faster than that allowance (the SPID Rot2Prog's nominal speed is 1 deg/s and one
exchange at 600 baud takes 0.42 s: a rotor at 30 deg/s, as test_session_doubt's "far faster than
its nominal speed" has it, turns 12 degrees between two answers asked at once) is never
confirmed while it turns: the rotator is shown offline with no bearing for the whole turn and
the idle poll after it, and R/error says "a noisy line or a failing position sensor" where the
line and the sensor are sound. Before the change it was online one exchange after the start,
though no better off: the first reading taken, the rest were doubted as readings at rest, the
bearing stayed at 21 for the whole turn and the same words were said; the change turned a wrong
bearing into none, but still never follows the turn (``_doubts_turning`` follows a turning
rotor after one doubt; ``_doubts_first`` at the usual polls allows no turn at all).

In virtual time: the emulated Rot2Prog turning by hand from 10 to 300 at 30 deg/s when the
bridge opens its port.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 30.0, "el_speed_deg_s": 30.0}  # as test_session_doubt's fast rotor
SHOWN_WITHIN_S = 3.0  # a few exchanges of 0.42 s: before the change, one


def test_a_rotor_turning_fast_when_the_bridge_starts_is_shown_at_once_and_not_called_noise(
    rig: Rig,
) -> None:
    v = rig("rot2prog", emulator={"start_az_deg": 10.0, **FAST}, connect=False)
    v.manual_rotate(300.0)  # (turning when the bridge opens the port: ten seconds of it)
    v.run_for(0.5)
    t = v.now
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 60, "the turn ends")
    shown = [
        (round(s_t - t, 2), s.bearing_deg)
        for s_t, s in v.statuses
        if s_t >= t and s.available and s.bearing_deg is not None
    ]
    assert shown and shown[0][0] <= SHOWN_WITHIN_S, (
        f"first bearing shown {shown[:1]} s after the port opened; the turn ended at "
        f"{v.now - t:.1f} s"
    )
    said = [e.message for e in v.errors(since=t)]
    assert not [m for m in said if "noisy line" in m or "line noise" in m], said


def test_a_replug_while_a_fast_rotor_turns_shows_it_at_once_and_calls_nothing_noise(
    rig: Rig,
) -> None:
    """The same after a replug mid-turn, the bridge's own turn to 300: before the change the
    first reading back was shown one exchange after the port came back (81 with the rotor at
    90, then followed), with no error; now nothing is shown until the rotor rests at 300,
    24 s later, and R/error blames the line or the sensor."""
    v = rig("rot2prog", emulator={"start_az_deg": 10.0, **FAST})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 30, "idle")
    v.target(300.0)
    v.run_until(lambda h: h.truth().az_deg > 60.0, 60, "turning")
    v.link_down()
    v.run_for(0.5)
    t = v.now
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 60, "the turn ends")
    shown = [
        (round(s_t - t, 2), s.bearing_deg)
        for s_t, s in v.statuses
        if s_t >= t and s.available and s.bearing_deg is not None
    ]
    assert shown and shown[0][0] <= SHOWN_WITHIN_S, (
        f"first bearing shown {shown[:1]} s after the port came back; the turn ended at "
        f"{v.now - t:.1f} s"
    )
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert not [m for m in said if "noisy line" in m or "line noise" in m], said
