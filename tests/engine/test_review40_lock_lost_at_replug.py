"""Review 40: the lock's stop to a rotor at rest is checked while the lock holds (stops.py
rule 2): a turn by hand at the panel of a locked rotor is fought, stopped a few degrees on
(test_attack9_turn_unseen_after_two_garbles.py). After the port is replugged, or the controller
answers again after a silence, the lock still holds, but nothing checks its stop any more: the
motion is rebuilt without it (motion.py ``link_down``: no ``stop_sent_t``), no stop is owed for
it (stops.py ``port_closed``: it was seen taken, long ago), and none is written again. A hand
at the panel then, tower work under way, turns the rotor from 150 to 300, the lock on all the
while and never fighting it. Now the controller answering again under the lock has its stop
written again, and checked as ever (stops.py rule 7)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.test_session_doubt import locked_at_rest
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def lose_the_readings(v: VirtualRotator, how: str) -> None:
    """The port replugged, or the controller silent until offline and back; then online."""
    if how == "replug":
        v.link_down()
        v.run_for(1.0)
        v.link_up()
    else:
        v.set_silent(True)
        v.run_until(lambda h: not h.status.available, 60, "offline")
        v.set_silent(False)
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")


@pytest.mark.parametrize("how", ["replug", "silence"])
@pytest.mark.parametrize("model", ["rotorez", "gs232b", "easycomm2", "rc2800"])
def test_a_turn_by_hand_on_a_locked_rotor_is_fought_after_the_readings_were_lost(
    rig: Rig, model: str, how: str
) -> None:
    v, rest = locked_at_rest(rig, model)
    lose_the_readings(v, how)
    v.run_for(20)
    t = v.now
    v.manual_rotate(300.0)  # a hand at the panel, the rotor locked
    v.run_for(60)
    assert v.status.locked
    assert MotionState.MOVING in {s.state for s in v.published(since=t)}  # (seen: followed)
    # what the lock does to the same turn before the readings were lost: fought within a few
    # degrees (159 on a Rotor-EZ)
    assert v.truth().az_deg < rest + 20
