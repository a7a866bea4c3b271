"""Attack 9: every STOP reaches the session twice, from the stop lane and as the main
connection's copy (lastword.py rule 1; the express writes a third frame of its own), and each
``SA SE`` goes out. K3NG's Easycomm firmware on an azimuth build refuses the ``SE`` of each with
a lone ``?`` (protocols/easycomm.py rule 7: harmless), but the two refusals come in one quiet
spell, and ``harmless`` takes only one ``?``: every STOP to such a box is followed on R/error by
'controller sent 6 bytes that are no valid reply', the box having answered as it always does."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.parametrize("model", ["easycomm2-az", "easycomm3-az"])
def test_a_k3ng_azimuth_builds_refusals_of_a_stops_se_are_told_nowhere(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"az_speed_deg_s": 6.0, "firmware": "k3ng"})
    v.run_until_state(MotionState.IDLE, 30)
    v.target(300)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 20, 30, "on")
    t = v.now
    v.stop()  # the stop lane's
    v.run_for(0.05)
    v.stop()  # the main connection's copy (lastword.py rule 1)
    v.run_until(lambda h: h.state is MotionState.IDLE, 10, "stopped")
    v.run_for(5)
    truth = v.truth()
    assert not truth.is_moving and v.sent(since=t).count(b"SA SE\n") == 2
    assert v.status.bearing_deg == pytest.approx(truth.az_deg, abs=0.051)
    assert v.errors(since=t) == []
