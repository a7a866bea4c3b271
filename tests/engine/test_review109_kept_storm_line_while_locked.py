"""Review 109 (Low): the line 730fe447 logs at a start in a storm kept in the state file
(runtime/kept.py rule 6, ``_storm_said``) says "parking again" for every storm whose park
was neither stopped nor seen reached. A storm begun while the rotator was locked has a park
that waits for the lock OFF (session/wind.py rules 4 and 9: "said waiting, never parked";
a review found the same words in the silence report a lie), and the lock is kept from the
file too: the start parks nothing.

What a user sees: the tower locked for work, a storm begins (its park waits for the lock
OFF), the bridge restarts; journalctl says "safety lock ON, kept from the state file" and
"... parking again (its park was not seen reached)", while the rotor does not move and
R/status says the park waits for the lock OFF. In virtual time, the file written by the
rotator's Kept as runtime/rotator.py has it, the next start's Kept and session made from it
as runtime/rotator.py makes them."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from bridge.core.model import MotionState
from tests.engine.kept_storm import kept, saved, session_from
from tests.engine.test_wind_park_offline import parking, storm


def test_a_start_locked_in_a_storm_does_not_say_it_parks(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / "state.json"
    v = parking()  # (a GS-232B at rest at 10 / 30, its wind park at 180 / 0)
    try:
        v.lock(True)  # the tower locked for work
        v.run_for(1.0)  # (the status after it: not a deadline)
        storm(v)  # its park waits for the lock OFF
        assert v.status.wind is not None and v.status.wind.storm and v.status.wind.waiting
        store = saved(v, path)  # (as runtime/rotator.py ``_status``)
        assert store.set_locked(v.cfg.rotator_id, True)  # (the lock ON saved, as ever)
        v.link_down(None)  # the bridge restarts
        here = v.truth().az_deg
        caplog.clear()
        with caplog.at_level(logging.INFO, logger="bridge"):
            again = kept(v, path)
        said = [r.getMessage() for r in caplog.records if "storm" in r.getMessage()]
        assert again.locked and again.storm
        v.session = session_from(v, again, locked=again.locked)
        v._do(v.session.start(v.now))
        v.link_up()
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "the controller answers")
        v.run_for(10.0)  # (the start's first seconds: not a deadline)
        assert abs(v.truth().az_deg - here) < 1.0  # nothing parked: the lock holds it
        assert v.status.wind is not None and v.status.wind.waiting
        assert said and not any("parking again" in line for line in said), said
    finally:
        v.close()
