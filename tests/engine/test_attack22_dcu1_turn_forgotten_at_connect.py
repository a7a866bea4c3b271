"""Attack 22: a DCU-1's connect forgets how long the turn under way may last: a replug mid-turn
(or a start while the box turns) cuts the bridge's own generous estimate to the span at the
nominal speed, and a rotor a quarter slower is still turning when the next target goes; the box
stops it there and ignores the bearing.

The DCU-1 cannot be asked where it is (motion.py rule 6): a turn the bridge sends is assumed to
last its travel "generous: 50 % slower than nominal plus two seconds to get going"
(``commanded``: 89.5 s for 350 degrees at 6 degrees a second), and a target meanwhile is
preceded by a stop and the brake delay. At every connect, ``link_up`` "cannot know whether it
is still turning or braking: assume the worst once", and puts in place of what it knew the span
at the nominal speed alone, 60 s from the connect, with no margin. A USB adapter that drops for
half a second one second into a 350-degree turn, on a rotor at 4.5 degrees a second (within
the half the bridge allows for), leaves the turn 78 s long and the bridge's window 61.5 s: a
target after it goes straight into the turn. The box, like the Rotor-EZ it is the subset of,
takes a bearing while it turns as a stop and otherwise ignores it (emulators/rotorez.py rule 5;
the bridge's own model: ``RetargetPolicy.STOP_AND_WAIT``): the antenna rests where the turn was
cut, about 290, never turned to 100, and with no feedback nobody is told. Without the replug
the same target is preceded by the stop and the brake delay and arrives.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.emulators.rotorez import Outcome
from bridge.session.motion import blind_busy_s
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
SLOWER = 4.5  # degrees a second: a quarter below the model's nominal 6
QUIET_S = 62.0  # the operator's pause before the next target (not a deadline)


@pytest.mark.parametrize("connect", ["replug mid-turn", "start mid-turn"])
def test_a_target_after_a_connect_mid_turn_never_goes_into_that_turn(
    rig: Rig, connect: str
) -> None:
    if connect == "replug mid-turn":
        v = rig("dcu1", emulator={"speed_deg_s": SLOWER})
        cfg = v.cfg.motion  # the start-up's own window over (not a deadline):
        v.run_for(blind_busy_s(cfg.az_span_deg, cfg) + cfg.brake_delay_s + 1)
        v.target(350)  # 0 to 350: 78 s at 4.5 deg/s
        v.run_for(1.0)
        v.link_down()
        v.run_for(0.5)
        v.link_up()
    else:  # the process before this one (killed, its host lost power) sent the turn
        v = rig("dcu1", connect=False, emulator={"speed_deg_s": SLOWER})
        v.device.receive(b"AP1350;", v.now)
        v.device.receive(b"AM1;", v.now)
        v.run_for(1.5)
        v.link_up()
    v.run_for(QUIET_S)
    assert v.truth().is_moving  # the turn runs on
    t = v.now
    v.target(100)
    v.run_for(120)  # (the turn to 100 and more: not a deadline)
    cut = v.frames(Outcome.IGNORED_RETARGET, Outcome.IGNORED_BRAKE_DELAY, since=t)
    assert cut == [], cut
    assert abs(v.truth().az_deg - 100) < 1, v.truth().az_deg
