"""Review 106 (Low): a storm kept in the state file (runtime/kept.py rule 4) turns the rotor at
the start, and nothing in the log says why. The lock kept is said at start ("safety lock ON,
kept from the state file", kept.py rule 6); a storm kept is not, and its park is the bridge's
own move: the wind park's "parking for the storm" is logged for a reading alone
(session/wind.py ``_stormy``), never for the storm a start takes from the file.

What a user sees: the bridge restarted (a crash, an update, a power blip) while the state
file says a storm whose park was not seen reached (the bridge died mid-park, a DCU-1's
every park, or a file copied from another station, an old backup put back); it turns the
rotor some 160 degrees to its park at 180 at once, before any wind reading; journalctl shows
"controller answering", "arrived at 180.0" and nothing that names a storm or the state
file. In virtual time, the file written by the rotator's Kept as runtime/rotator.py has it,
the next start's Kept and session made from it as runtime/rotator.py makes them."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from bridge.core.model import MotionState
from bridge.runtime.kept import Kept
from bridge.runtime.state_store import StateStore
from tests.engine.kept_storm import kept, saved, session_from
from tests.engine.test_wind_park_offline import WIND, parking, storm


def test_a_start_in_a_storm_kept_in_the_state_file_says_so_in_the_log(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / "state.json"
    v = parking()  # (a GS-232B at rest at 10 / 30, its wind park at 180 / 0)
    try:
        assert WIND["park_az_deg"] == 180
        storm(v)  # two seconds into the park: the bridge dies here
        saved(v, path)  # (as runtime/rotator.py ``_status``)
        v.power_cycle()  # (the controller's turn ends with the power)
        v.link_down(None)
        v.run_for(1.0)  # (the bridge down: not a deadline)
        here = v.truth().az_deg
        caplog.clear()
        with caplog.at_level(logging.INFO, logger="bridge"):
            again = kept(v, path)
            assert again.storm
            v.session = session_from(v, again)
            v._do(v.session.start(v.now))
            v.link_up()
            v.run_until(
                lambda h: abs(h.truth().az_deg - 180.0) < 1.0 and h.state is MotionState.IDLE,
                120,
                "at its park, sent by the start",
            )
        assert abs(here - 180.0) > 90.0, here  # (the start turned it: not a small move)
        said = [r.getMessage() for r in caplog.records if r.levelno >= logging.INFO]
        assert any("storm" in line.lower() for line in said), said
    finally:
        v.close()


@pytest.mark.parametrize(
    ("halted", "arrived", "wind", "words"),
    [
        (True, False, True, "its park, stopped by a STOP or lock ON, is not sent again"),
        (False, True, True, "its park was reached: not sent again"),
        (False, False, False, "a storm kept from the state file is let go: no wind_topic"),
    ],
)
def test_what_a_start_does_with_a_kept_storm_is_what_the_log_says(
    tmp_path: Path,
    caplog: pytest.LogCaptureFixture,
    halted: bool,
    arrived: bool,
    wind: bool,
    words: str,
) -> None:
    """Not "parking again" where the start parks nothing (kept.py rule 4: a park a STOP
    stopped, or one seen reached, is not sent again; a storm with no wind topic configured
    any more is let go: session.py ``WindPark``)."""
    path = tmp_path / "state.json"
    store = StateStore(path)
    assert store.set_storm("tower", True, halted=halted, arrived=arrived, place=0)
    v = parking()
    try:
        with caplog.at_level(logging.INFO, logger="bridge"):
            Kept(StateStore(path), "tower", v.cfg.spec, report=lambda *a: None, wind=wind)
        said = [r.getMessage() for r in caplog.records if r.levelno >= logging.INFO]
        assert any(words in line for line in said), said
        assert not any("parking again" in line for line in said), said
    finally:
        v.close()
