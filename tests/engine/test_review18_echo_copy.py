"""Cold review 18: the main connection's copy of a STOP the stop lane already carried out
(lastword.py rules 2 and 9: halts.py knows it is that copy, ``Copy.echo``) is put in the mailbox
as a full STOP, and drops a target another front end sent *after* that STOP (rotctld's, the
console's, a logger's), which waited only for the lane's hold. lastword.py rule 2 says the copy
"drops every target older than it"; this target is newer than the STOP both copies stand for:
the newest word on the rotator is lost, without a word to the client that sent it.

Virtual time, the Rotor-EZ emulator (tests/engine/virtual.py), the two MQTT connections stood
in for by what they put in the mailbox, as tests/engine/test_session_last_word.py does.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState, Source, Stop, Target
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
IDLE = MotionState.IDLE


def test_the_main_copy_of_a_lane_stop_does_not_drop_a_newer_rotctld_target(rig: Rig) -> None:
    v = rig("rotorez")
    v.run_until_state(IDLE, 30)
    v.target(200)
    v.run_until(lambda h: h.truth().is_moving, 10, "turning")
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # the operator's STOP, read on the stop lane
    v._take()
    v.run_for(3)
    assert not v.truth().is_moving
    # a second later the rotctld client (the operator's logger) turns the rotor to 250: newer
    # than the STOP; it waits for the lane's hold (the main connection is behind a backlog)
    v.mailbox.put(Target(250.0, None, Source.ROTCTLD))
    v._take()
    v.run_for(3)
    # the main connection reaches its copy of the STOP (halts.py: ``copy.echo``), then the marker
    v.mailbox.put(Stop(Source.MQTT))
    v._take()
    v.mailbox.put_release(1)
    v._take()
    v.run_until(
        lambda h: h.state is IDLE and abs(h.truth().az_deg - 250) < 4,
        120,
        "at 250: the rotctld target sent after the STOP",
    )


def test_the_main_copy_of_a_lane_lock_on_does_not_undo_a_newer_console_lock_off(rig: Rig) -> None:
    """The same for the lock: the lane's lock ON, then the console's lock OFF (newer: the
    operator is off the tower), then the main connection's copy of that same lock ON locks
    the rotator again, behind the console's back."""
    v = rig("rotorez")
    v.run_until_state(IDLE, 30)
    v.mailbox.put_lock(True, hold=1)  # the lane's lock ON
    v.mailbox.put_lock_saved(True)
    v._take()
    v.lock(False)  # the console's lock OFF, a minute later
    assert not v.status.locked
    v.mailbox.put_lock(True)  # the main connection's copy of the lane's lock ON (the echo)
    v.mailbox.put_lock_saved(True)
    v._take()
    v.mailbox.put_release(1)
    v._take()
    v.run_for(2)
    assert not v.status.locked, "the echo of the older lock ON undid the newer lock OFF"
