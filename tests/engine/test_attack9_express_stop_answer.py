"""Attack 9: the stop express (interfaces/mqtt/express.py, on by default) writes a STOP's
frame on its own copy of the port, ahead of the session's, and the codec never hears of it. A
SatNOGS controller answers ``SA SE`` with its position (protocols/easycomm.py rule 9); the
codec takes a position line with no query open for a stop's answer only once it has seen this
controller answer one of its own stops. So at the first STOP of a connection the answer to the
express's frame is a 'position nobody asked for': it spoils the reading held (asked again) and
is told on R/error as bytes that are no valid reply, although the controller answered the
user's STOP as its firmware does."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def express_stop(v: VirtualRotator) -> None:
    """The express's copy of the stop frame: on the wire now, written past the session."""
    frame = v.cfg.spec.codec_factory().encode_stop()
    assert isinstance(frame, bytes)
    v._tx.send(frame, v.now)  # (the express's os.write on its copy of the port's descriptor)


def test_a_satnogs_answer_to_the_express_stop_is_no_junk(rig: Rig) -> None:
    v = rig(
        "easycomm2",
        emulator={"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0, "firmware": "satnogs"},
    )
    v.run_until_state(MotionState.IDLE, 30)
    v.target(300, 20)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 20, 30, "on")
    t = v.now
    express_stop(v)  # the user's STOP: the express's frame first ...
    v.run_for(0.05)
    v.stop()  # ... and the session's own, from the stop lane
    v.run_until(lambda h: h.state is MotionState.IDLE, 10, "stopped")
    v.run_for(5)
    truth = v.truth()
    assert not truth.is_moving
    assert v.status.bearing_deg == pytest.approx(truth.az_deg, abs=0.051)
    assert v.errors(since=t) == []
