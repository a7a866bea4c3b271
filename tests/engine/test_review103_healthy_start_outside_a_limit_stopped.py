"""Review 103: a healthy controller whose rotor rests outside a configured limit gets a stop and
a stop error at every start and replug.

controller.py rule 9 (``_first_past_limit``, commit e9e2e51a) sends a stop for a connection's
first reading not yet confirmed by another that, if true, is past a limit by more than
``tolerance_deg + noise_deg``, and says so on R/error. It does so before the next reading is
asked, on a clean line too: a rotor left at rest at 30 (by a hand at the panel, or before
``az_min_deg`` was raised to 60) reads 30 at the first answer and 30 at the second, and every
start of the bridge and every replug of its port writes a stop to it and publishes "a first
reading of 30/0, not yet confirmed by another, is past az_min_deg if true: stopped". Before the
change it was shown at 30 with no stop and no error. The stop is harmless at rest, but the
error is false (the reading is confirmed a reply later and the error stands); and a GS-232B
turning from 30 back inside the limit when the bridge starts (sent to 180 before a restart) is
stopped at 33 and left outside its limit, where before the change it reached 180.

In virtual time: a GS-232B, an Easycomm II and a Rot2Prog box at rest at 30 (and the GS-232B
turning from 30 to 180), ``az_min_deg`` 60, a clean line.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import ErrorKind
from tests.engine.garblers import limited
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 30.0
AZ_MIN_DEG = 60.0
WATCH_S = 5.0  # several replies of the slowest of them (virtual time)


@pytest.mark.parametrize("model", ["gs232b", "easycomm2", "rot2prog"])
def test_a_healthy_start_outside_a_limit_writes_no_stop_and_says_no_stop(
    rig: Rig, model: str
) -> None:
    v = limited(rig, model, REST_DEG, AZ_MIN_DEG)
    v.link_up()
    v.run_for(WATCH_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG
    stops = [e.message for e in v.errors() if e.kind == ErrorKind.STOP]
    assert v.frames("stop") == [] and stops == [], stops


def test_a_turn_back_inside_the_limit_when_the_bridge_starts_is_not_cut(rig: Rig) -> None:
    v = limited(rig, "gs232b", REST_DEG, AZ_MIN_DEG)
    v.device.receive(b"M180\r", v.now)  # (sent before the restart: turning back inside)
    v.run_for(0.5)  # (the turn under way: not a deadline)
    assert v.truth().is_moving
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 60, "the turn ends")
    assert v.truth().az_deg == pytest.approx(180.0, abs=1.0), [e.message for e in v.errors()]
