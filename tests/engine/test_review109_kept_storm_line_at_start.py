"""Review 109 (Low): the line 730fe447 logs at a start in a storm kept in the state file
(runtime/kept.py rule 6, ``_storm_said``) says what the start does with the storm's park from
the file's ``halted`` first. But a STOP after the park was seen reached sets ``halted`` too
(session/wind.py ``halted``: the status's ``halted`` and ``arrived`` both true; rule 1: such
a stop "stopped no park: still 'parked for the storm'"), so the file holds both.

What a user sees: parked for the storm, the rotor at its park, the operator presses STOP (or
turns the lock ON and OFF for tower work); the bridge restarts, and journalctl says "its park,
stopped by a STOP or lock ON, is not sent again" while R/status and every refusal say
"parked for the storm", the rotor standing at its park. In virtual time, the file written by
the rotator's Kept as runtime/rotator.py has it, the next start's Kept and session made from
it as runtime/rotator.py makes them."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from bridge.core.model import MotionState
from tests.engine.kept_storm import kept, saved, session_from
from tests.engine.test_wind_park_offline import parking, storm


def test_a_stop_after_the_park_was_reached_is_no_park_stopped_in_the_start_line(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / "state.json"
    v = parking()  # (a GS-232B at rest at 10 / 30, its wind park at 180 / 0)
    try:
        storm(v)
        v.run_until(
            lambda h: h.status.wind is not None and h.status.wind.arrived,
            120,
            "seen at its park",
        )
        v.stop()  # the operator's STOP, the rotor at its park
        v.run_for(2.0)  # (the status after it: not a deadline)
        assert v.status.wind is not None and v.status.wind.halted and v.status.wind.arrived
        assert v.status.wind.refusal is not None and "parked for the storm" in v.status.wind.refusal
        saved(v, path)  # (as runtime/rotator.py ``_status``)
        v.link_down(None)  # the bridge restarts
        caplog.clear()
        with caplog.at_level(logging.INFO, logger="bridge"):
            again = kept(v, path)
        said = [r.getMessage() for r in caplog.records if "storm" in r.getMessage()]
        v.session = session_from(v, again)
        v._do(v.session.start(v.now))
        v.link_up()
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "the controller answers")
        v.run_for(2.0)  # (the status after it: not a deadline)
        wind = v.status.wind
        assert wind is not None and wind.refusal is not None
        assert "parked for the storm" in wind.refusal, wind.refusal  # what the status says
        assert said and not any("stopped by a STOP" in line for line in said), said
    finally:
        v.close()
