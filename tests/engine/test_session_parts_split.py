"""Behaviour the split of the session into parts (controller.py, stops.py, options.py,
targets.py, tracking.py, autopark.py) must keep, in virtual time: each scenario here once
changed with the split, and each passes on the session before it."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState, Source, Stop
from bridge.sky import Body, Sky
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
SUN_EPOCH = 1_781_000_000.0  # as test_session_tracking.py: a fixed sky, the sun up at 0N 60E


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


def test_a_tracking_target_dropped_when_the_controller_falls_silent_is_reported(
    rig: Rig,
) -> None:
    """Session rule 4 / controller.py rule 2: a controller that stops answering drops the
    target that waits, and says so, whoever put it (tracking's own included): the error names
    the target that never went out."""
    v = rig("rotorez", sky=Sky(0.0, 60.0), wall_epoch_s=SUN_EPOCH)
    v.run_until_state(MotionState.IDLE, 30)
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # the stop lane's stop: held until marker 1
    v._take()
    v.track(Body.sun())  # tracking's first target waits for the marker (session rule 13)
    v.run_for(1)
    assert v.status.target_az_deg is not None and v.status.tracking is not None
    v.set_silent(True)  # the controller hears, but no reading comes back any more
    v.run_until(lambda h: not h.status.available, 10, "offline")
    assert v.status.tracking_ended == "controller not answering"
    dropped = [e for e in v.errors("refused") if "target dropped" in e.message]
    assert [e.message for e in dropped] == ["target dropped: controller not answering"]
    assert dropped[0].command is not None and dropped[0].command.startswith("target az")
    assert v.status.last_error == "target dropped: controller not answering"


def test_tracking_waits_out_the_settle_time_on_a_rotor_without_a_brake(rig: Rig) -> None:
    """Tracking sends nothing while the rotor may still be turning at start-up (motion rule 4):
    an MD-01 has no brake, so it is shown idle meanwhile (motion.settling), yet tracking's
    first target still goes out only settle_s after the first reading, as it did while such a
    rotor was shown braking."""
    v = rig("md01", sky=Sky(0.0, 60.0), wall_epoch_s=SUN_EPOCH, emulator={"start_az_deg": 100})
    v.run_until(lambda h: h.status.available, 10, "the first reading")
    first_reading_t = v.now
    v.track(Body.sun())
    v.run_until(lambda h: h.status.target_az_deg is not None, 10, "tracking's first target")
    codec = v.cfg.spec.codec_factory()
    query = codec.encode_query()
    targets = [w.t for w in v.writes if w.t >= first_reading_t and w.data != query]
    assert targets and min(targets) >= first_reading_t + v.cfg.motion.settle_s - 1e-9
