"""Cold review 18: the main connection's copy of a STOP the stop lane already carried out
(lastword.py rules 2 and 9: halts.py knows it is that copy, ``Copy.echo``) was put in the
mailbox as a full STOP, and dropped a target another front end sent *after* that STOP (rotctld's,
the console's, a logger's), which waited only for the lane's hold. lastword.py rule 2 says the
copy "drops every target older than it"; this target is newer than the STOP both copies stand
for: the newest word on the rotator was lost, without a word to the client that sent it.

Virtual time, the Rotor-EZ emulator (tests/engine/virtual.py), the two MQTT connections through
the service (service.py, halts.py, lastword.py), whose calls go to the session's mailbox as
runtime/rotator.py would put them (``Bridged``); the other front end's command put in the
mailbox as its judge would. (The review's first form put the copy in the mailbox as halts.py
did then, a plain STOP: the session cannot tell that from a real one, so the copy is now
decided where it is known for one, halts.py, and the test goes through it.)
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState, Source, Target
from bridge.interfaces.mqtt.service import MqttService
from tests.engine.test_review18_lost_main_copy import Bridged
from tests.engine.virtual import VirtualRotator
from tests.mqtt.test_service import RecordingPublisher, service

Rig = Callable[..., VirtualRotator]
IDLE = MotionState.IDLE


def bridged(v: VirtualRotator) -> tuple[MqttService, RecordingPublisher]:
    svc, pub, _ = service({"tower": "rotorez"})
    tower = Bridged("tower", "rotorez")
    tower.v = v
    svc.attach(tower)
    pub.take()
    return svc, pub


def lane(svc: MqttService, pub: RecordingPublisher, topic: str, payload: bytes) -> bytes:
    """A halt read on the stop lane: the marker it sent on the main connection."""
    svc.on_lane_message(topic, payload, False)
    (marker,) = [m for m in pub.take() if m[0] == "rotor/bridge/fence"]
    return marker[1].encode()


def test_the_main_copy_of_a_lane_stop_does_not_drop_a_newer_rotctld_target(rig: Rig) -> None:
    v = rig("rotorez")
    v.run_until_state(IDLE, 30)
    svc, pub = bridged(v)
    v.target(200)
    v.run_until(lambda h: h.truth().is_moving, 10, "turning")
    marker = lane(svc, pub, "rotor/stop", b"")  # the operator's STOP, read on the stop lane
    v.run_for(3)
    assert not v.truth().is_moving
    # a second later the rotctld client (the operator's logger) turns the rotor to 250: newer
    # than the STOP; it waits for the lane's hold (the main connection is behind a backlog)
    v.mailbox.put(Target(250.0, None, Source.ROTCTLD))
    v._take()
    v.run_for(3)
    # the main connection reaches its copy of the STOP (halts.py: ``copy.echo``), then the marker
    svc.on_message("rotor/stop", b"", False)
    svc.on_message("rotor/bridge/fence", marker, False)
    v.run_until(
        lambda h: h.state is IDLE and abs(h.truth().az_deg - 250) < 4,
        120,
        "at 250: the rotctld target sent after the STOP",
    )


def test_the_main_copy_of_a_lane_lock_on_does_not_undo_a_newer_console_lock_off(rig: Rig) -> None:
    """The same for the lock: the lane's lock ON, then the console's lock OFF (newer: the
    operator is off the tower), then the main connection's copy of that same lock ON locked
    the rotator again, behind the console's back."""
    v = rig("rotorez")
    v.run_until_state(IDLE, 30)
    svc, pub = bridged(v)
    marker = lane(svc, pub, "rotor/lock", b"ON")  # the lane's lock ON
    assert v.status.locked
    v.lock(False)  # the console's lock OFF, a minute later
    assert not v.status.locked
    svc.on_message("rotor/lock", b"ON", False)  # the main connection's copy of the lane's ON
    svc.on_message("rotor/bridge/fence", marker, False)
    v.run_for(2)
    assert not v.status.locked, "the echo of the older lock ON undid the newer lock OFF"
