"""Review 93 (b1e284e5, motion.py rule 4): "a restart's found turn waits for each axis's own
time, not rule 2's settle_s; only a settle_s the user set cuts it short". ``settle_own`` is
whether the key is written in the config at all (app.py: ``"settle_s" in model_fields_set``),
not whether the value is short: a config that writes out the default, ``settle_s = 1.5`` (as
a copied or generated config does), cuts the wait to rule 2's rest again, the very value review
89 found too short for this rotor. So review 89's case comes back for that user:
after a restart mid elevation-only turn (a GS-232B elevation at 2.0 deg/s), a follow start
refused at once sends no stop, R/error says only that the start was refused, the elevation
turns on 23 -> 85 to the old bridge's target, and following ends "turned by hand" though
nobody touched the panel. With the key left out the same turn is halted (review 89's test)."""

from __future__ import annotations

from tests.engine.test_review89_restart_mid_slow_elevation_turn import (
    gs232_with_a_slow_elevation_by_a_keep_out,
    refused_right_after_a_restart_mid_the_elevation_turn,
)
from tests.engine.virtual import VirtualRotator


def gs232_with_settle_s_written(settle_s: float) -> VirtualRotator:
    """Review 89's GS-232B az/el by a keep-out sector, its elevation turning at 2.0 deg/s,
    with ``settle_s`` written in its config."""
    return gs232_with_a_slow_elevation_by_a_keep_out(settle_s=settle_s)


def test_the_default_settle_s_written_in_the_config_still_halts_a_restarts_slow_turn() -> None:
    with gs232_with_settle_s_written(1.5) as v:
        t, here = refused_right_after_a_restart_mid_the_elevation_turn(v)
        # held where it was (a stop and its coast): observed 23 -> 85, no stop frame
        assert abs(v.truth().el_deg - here) <= 10.0, (here, v.truth().el_deg)
        assert "stop" in {f.outcome for f in v.frames(since=t)}
        # taken, and waiting for a grid it may turn to: observed ended "turned by hand"
        assert v.status.following is not None, v.status.following_ended
