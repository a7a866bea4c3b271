"""Review 107: a Rotor-EZ turn the unwatched stop cut short after a replug is not guarded: a
poll garbled into ``AM1;`` later runs the rotor on to the target it was stopped short of.

controller.py rule 10 (``unasked_moves`` "after-stop", the Rotor-EZ's): the board keeps the
bearing of its last target, and one flipped bit makes a poll (``AI1;``) the command to turn to
it (``AM1;``); so the first turn nobody asked for after the rotor rested short of the last
target written (a STOP or a lock mid-turn) is stopped, and that target is in the status
(``short_of_deg``). Rule 9's unwatched stop (commits 025ee699, 110b095c) is such a stop: the
port replugged mid-turn, the line garbling every answer, the bridge stops the turn ("the rotor
was stopped", R/error) short of its target. Once the line is sound the rotor rests there, the
status shows no ``short_of_deg``, and the next poll garbled into ``AM1;`` turns it on to the
target, 180 degrees, unstopped and unsaid. (An operator's STOP while the port was out, written
at the reconnect, leaves the same hole: the replug forgets the guard.)

In virtual time: the emulated Rotor-EZ at 90, sent to 300; the port unplugged at about 108 and
plugged back half a second later, every position answer then off by 0, +60 or -60 in turn for
three seconds; then the line is sound, and twenty seconds later one poll reaches the board as
``AM1;``.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import every_rotorez_answer_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 90.0
TARGET_DEG = 300.0
OFFSETS = [0.0, 60.0, -60.0]
TURNING_S = 8.0  # the turn under way when the port drops (virtual time)
UNPLUGGED_S = 0.5  # (virtual time)
GARBLED_S = 3.0  # the reconnect's readings disagree: the unwatched stop written (virtual time)
REST_S = 20.0  # the sound line's readings: the rotor at rest where it was stopped (virtual)
WATCH_S = 60.0  # a turn on to 300 at the Rotor-EZ's speed, with room (virtual time)
JOG_STOPPED_DEG = 30.0  # rule 10 stops a jog UNASKED_MOVE_DEG on, with room
POLL = b"AI1;"
JOG = b"AM1;"  # one flipped bit: turn to the stored target


def test_a_turn_cut_short_by_the_unwatched_stop_is_not_run_on_by_a_garbled_poll(
    rig: Rig,
) -> None:
    v = rig("rotorez", emulator={"start_az_deg": START_DEG})
    v.run_until(lambda h: h.status.available, REST_S, "the controller answers")
    v.target(TARGET_DEG)
    v.run_for(TURNING_S)
    assert v.truth().is_moving
    v.link_down()
    v.run_for(UNPLUGGED_S)
    v.to_host = every_rotorez_answer_off(OFFSETS)
    v.link_up()
    v.run_for(GARBLED_S)
    v.to_host = None
    v.run_for(REST_S)
    rest = v.truth().az_deg
    assert not v.truth().is_moving and rest < TARGET_DEG - 90, rest  # (the unwatched stop's)
    assert v.status.available and v.status.bearing_deg is not None
    t = v.now
    v.garble_writes(POLL, JOG)  # (one flipped bit on the next poll)
    v.run_for(WATCH_S)
    said = [e.message for e in v.errors(since=t)]
    assert v.truth().az_deg < rest + JOG_STOPPED_DEG, (
        f"stopped by the bridge at {rest:.0f} short of {TARGET_DEG:g} (short_of_deg "
        f"{v.status.short_of_deg}), the rotor ran on to {v.truth().az_deg:.0f} on one garbled "
        f"poll; said: {said}"
    )
