"""A SatEL's nudges on the wire (pointing.py rule 6 on a controller of ten-degree steps,
protocols/satel.py rule 7): a nudge goes to the nearest step of the value it names and at
least one step its own way, so -5 at 120 turns the rotor to 110 as +5 turns it to 130, and
two quick presses end two steps on. Rounded half up alone, -5 at 120 was 115 and went out as
``p120``: nothing turned. The judge every front end calls (runtime/rotator.py) over the real
session and the SatEL emulator turned as built (ten-degree steps), in virtual time
(tests/engine/virtual.py); what is asserted is the point on the wire and where the rotor ends."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.core.model import MotionState, Nudge, Origin, Source
from bridge.emulators.satel import Outcome
from tests.engine import test_small_nudges as small
from tests.engine.virtual import settled_at

WHO = Origin(Source.MQTT)
START = {"step_deg": 10, "start_az_deg": 120, "start_el_deg": 20}


class Judged(small.Judged):
    """A Rotator on a virtual SatEL at rest at 120/20; the Rotator takes the mailbox."""

    def __init__(self, tmp_path: Path) -> None:
        super().__init__(tmp_path, "satel", START)
        self.v.run_until_state(MotionState.IDLE, 30)

    def nudge(self, d_az: float, d_el: float | None = None) -> None:
        self.rot.submit(Nudge(d_az, d_el, source=Source.MQTT, origin=WHO), f"nudge {d_az:+g}")
        self.v._take()

    def points(self) -> list[bytes]:
        return [f.data for f in self.v.frames(Outcome.SLEW)]


@pytest.fixture
def judged(tmp_path: Path) -> Iterator[Judged]:
    made = Judged(tmp_path)
    yield made
    made.close()


@pytest.mark.parametrize(("d_az", "step"), [(-5.0, 110.0), (5.0, 130.0), (-12.0, 110.0)])
def test_a_small_nudge_at_rest_turns_one_step_either_way(
    judged: Judged, d_az: float, step: float
) -> None:
    judged.nudge(d_az)
    judged.v.run_until(settled_at(step, 20), 60, f"at {step}")
    assert judged.points() == [b"p%d 20\r" % step]
    assert judged.v.status.bearing_deg == step
    assert not judged.events


@pytest.mark.parametrize(("d_az", "steps"), [(5.0, (130.0, 140.0)), (-5.0, (110.0, 100.0))])
def test_two_quick_presses_end_two_steps_on(
    judged: Judged, d_az: float, steps: tuple[float, float]
) -> None:
    """The second press comes while the first step is still approached: it counts from that
    step (the status's target, as sent), not from the bearing, nor from the value named."""
    judged.nudge(d_az)
    judged.v.run_until(lambda v: v.state is MotionState.MOVING, 10, "turning")
    assert judged.v.status.target_az_deg == steps[0]
    judged.nudge(d_az)
    judged.v.run_until(settled_at(steps[1], 20), 60, f"at {steps[1]}")
    assert judged.points()[0] == b"p%d 20\r" % steps[0]
    assert judged.points()[-1] == b"p%d 20\r" % steps[1]
    assert judged.v.status.bearing_deg == steps[1]
    assert not judged.events


def test_an_elevation_nudge_turns_one_step_too(judged: Judged) -> None:
    judged.nudge(0.0, -5.0)
    judged.v.run_until(settled_at(120, 10), 60, "at 120/10")
    assert judged.points() == [b"p120 10\r"]
    assert judged.v.status.elevation_deg == 10
    assert not judged.events
