"""Attack 9: a STOP pressed at rest, then the readings lost before one showed it taken (the
port replugged, the line gone silent): the first reading back was not doubted against where
the rotor stood (session/controller.py rule 9), and one flipped bit in it was published as the
bearing and taken as a turn. (``_lose_motion`` kept the rotor's stillness only where no stop was
sent: ``m.stop_sent_t is None``; a stop to a rotor at rest leaves it as still as it was.)
An RT-21 is left out: its replies have no head the flip can find (``flip_next_hundreds``)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.test_session_doubt import MODELS, at_rest, flip_next_hundreds
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.parametrize("model", [m for m in MODELS if m != "rt21"])
def test_a_flipped_first_reading_after_a_stop_at_rest_and_a_replug_is_never_taken(
    rig: Rig, model: str
) -> None:
    v = at_rest(rig, model)
    rest = v.status.bearing_deg
    v.stop()  # a user's STOP to a rotor at rest (harmless: controller.py rule 2)
    v.link_down()  # ... and the adapter drops out before a reading showed the stop taken
    v.run_for(2.0)
    t = v.now
    flipped = flip_next_hundreds(v)
    v.link_up()
    v.run_until(lambda h: bool(flipped) and h.status.available, 60, "back, the flipped reply")
    v.run_for(20)
    assert {s.bearing_deg for s in v.published(since=t)} - {None} == {rest}
    assert MotionState.MOVING not in {s.state for s in v.published(since=t)}
    assert v.status.bearing_deg == rest and v.state is MotionState.IDLE
