"""Review 32: status.py rule 1 after 1a4e3237. A RotorCard (its travel ends at north) at its
360 end reads 000 (rotorez.py rule 3's board: tests/emulators/test_rotorez_wire.py, 360 reads
``;000``); sent from there to 200 it turns down the scale, 160 degrees. Read at 000, then at
200 (the bridge's process held: 1a4e3237's own scenario, at the other end), the new rule takes
the way towards the target from the published 0, +1, though the rotor went down from 360
(-1, as the shorter way round said before). Its jitter at rest, 201, is then a step on "the
way it went", shown as the turn's last degree for good, the rotor at 200: the demo's bug
1a4e3237 fixed at 0, brought to the 360 end. Before 1a4e3237 the first test passes."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from bridge.session.status import Hysteresis
from tests.engine.virtual import VirtualRotator


def test_a_rotorcard_parked_at_360_and_sent_down_is_shown_where_it_rests(
    rig: Callable[..., VirtualRotator],
) -> None:
    v = rig("rotorcard", emulator={"start_az_deg": 360.0})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 30, "online")
    v.run_for(3)
    assert v.status.raw_bearing_deg == 0.0  # (the 360 end, read as 000)
    v.target(200.0)
    v.pause(40)  # the bridge's process held (SIGSTOP, a host that stalls) through the turn
    v.run_for(30)
    assert v.truth().az_deg == 200.0 and not v.truth().is_moving
    assert v.status.raw_bearing_deg == 200.0


def test_a_turn_down_from_the_360_end_read_as_000_shows_its_last_degree() -> None:
    shown = Hysteresis()
    shown.feed(0, False, 2, True, False)  # at the 360 end, read as 000
    shown.feed(201, True, 2, True, False, toward=200)  # polls late: the next reading
    shown.feed(200, False, 2, True, True, toward=200)  # found still: its last degree
    assert shown.value == 200
