"""A nudge smaller than the rotator's tolerance turns the rotor by that much, and presses add up
(session/targets.py rule 5: a nudge is no target already reached). An attack pass: a Rotor-EZ
resting at 100 with the default tolerance of 3 degrees was nudged +2 five times, 1.5 s apart:
each was said carried out and not one frame went to the controller; a GS-232B took the first and
none after it (each counted from where the one before had left the rotor, within tolerance).
The judge every front end calls (runtime/rotator.py) and the real session on a virtual
controller (tests/engine/virtual.py), as tests/engine/test_halt_epoch.py's bench."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.core.model import ErrorEvent, Nudge, Origin, Source, Target
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from tests.engine.virtual import VirtualRotator

WHO = Origin(Source.MQTT)
START = 100.0
MODELS: dict[str, dict[str, Any]] = {
    "rotorez": {"start_az_deg": START, "jitter_deg": 0},
    "gs232b": {"start_az_deg": START},
    "rot2prog": {"start_az_deg": START},
}


class Judged:
    """A Rotator on a virtual controller at rest at START; the test takes its mailbox."""

    def __init__(self, tmp_path: Path, model: str, emulator: dict[str, Any] | None = None) -> None:
        self.v = VirtualRotator(model, emulator=MODELS[model] if emulator is None else emulator)
        self.v.run_until(lambda h: h.status.available, 10, "the controller answers")
        self.events: list[ErrorEvent] = []
        self.rot = Rotator(
            self.v.cfg, StateStore(tmp_path / "state.json"), lambda s: None, self.events.append
        )
        self.v.mailbox.close()
        self.v.mailbox = self.rot._mailbox
        self.rot._worker.session = self.v.session

    def close(self) -> None:
        self.rot.operators.stop()
        self.v.close()

    def submit(self, command: Nudge | Target, what: str) -> None:
        self.rot.submit(command, what)
        self.v._take()

    def rests(self) -> None:
        """Until the status says the rotor is idle again (its brake delay over)."""
        self.v.run_until(lambda h: h.status.state.value == "idle", 60, "the rotor rests")


@pytest.fixture(params=sorted(MODELS))
def judged(tmp_path: Path, request: pytest.FixtureRequest) -> Iterator[Judged]:
    made = Judged(tmp_path, request.param)
    yield made
    made.close()


def test_five_nudges_smaller_than_the_tolerance_turn_the_rotor_by_all_five(
    judged: Judged,
) -> None:
    assert judged.v.cfg.motion.tolerance_deg > 2.0  # (the defaults: the nudge is within it)
    judged.v.run_for(2.0)
    for _ in range(5):
        judged.submit(Nudge(2.0, None, source=Source.MQTT, origin=WHO), "nudge '+2'")
        judged.v.run_for(1.5)
        judged.rests()
    truth = judged.v.truth().az_deg
    assert truth == pytest.approx(START + 10.0, abs=1.0)
    assert judged.rot.status.bearing_deg == pytest.approx(START + 10.0, abs=1.0)
    assert not judged.events  # nothing refused, no stall, no turn nobody asked for


def test_a_target_within_the_tolerance_of_where_the_rotor_rests_is_still_not_sent(
    judged: Judged,
) -> None:
    """What rule 5 is for stays: an absolute target the rotor already rests within the
    tolerance of writes no frame."""
    judged.v.run_for(2.0)
    sets = len(judged.v.frames("set"))
    judged.submit(Target(START + 2.0, None, Source.MQTT, origin=WHO), "target '102'")
    judged.v.run_for(5.0)
    assert len(judged.v.frames("set")) == sets
    assert judged.v.truth().az_deg == pytest.approx(START, abs=1.0)
