"""Behaviour the split of the session into parts (controller.py, stops.py, options.py,
sending.py, tracking.py, autopark.py) must keep, in virtual time: each scenario here once
changed with the split, and each passes on the session before it."""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_options_wait_for_the_settle_time_on_a_rotor_without_a_brake(rig: Rig) -> None:
    """options.py rule 1: options go out only while the rotor is idle, and at start-up it may
    be turning until settle_s of stillness has been seen. A rotor without a brake is shown
    idle meanwhile (motion.settling), but is no more ready for the letters than it was."""
    v = rig(
        "rotorez",
        settings={"brake_delay_s": 0},
        options={"jam": False, "overshoot": True},
    )
    v.run_until(lambda h: h.status.available, 10, "the first reading")
    first_reading_t = v.now
    v.run_for(5)
    codec = v.cfg.spec.codec_factory()
    letters = {codec.encode_option("jam", False), codec.encode_option("overshoot", True)}
    sent = [w.t for w in v.writes if w.data in letters]
    assert len(sent) == 2
    assert min(sent) >= first_reading_t + v.cfg.motion.settle_s - 1e-9, (sent, first_reading_t)
