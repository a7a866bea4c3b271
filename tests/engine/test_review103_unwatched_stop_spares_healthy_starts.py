"""Reviews 100 and 103: first readings that never confirm get a stop; a start that confirms
does not, and a line that comes right is confirmed after its stops.

controller.py rule 9 (``_unwatched_stop``): FIRST_UNWATCHED_READINGS first readings in a row
that confirmed none mean the bridge cannot watch the rotor, and it is stopped (again at each as
many more, said once a junk interval). The count must
stay above what a healthy start needs: a rotor turning faster than its nominal speed allows
confirms only on four readings on one steady line (``_steady``), and one garbled answer among
them breaks the line, so that start takes seven unconfirmed answers before the eighth confirms
(a stop at a lower count cut such a turn short with a false "do not agree" error). And the stops
are no verdict on the line for good: once the answers agree again, the controller is shown with
its bearing.

In virtual time: the emulated Rot2Prog turning by hand from 10 to 300 at 30 deg/s when the
bridge opens its port, its fourth position frame reaching the host 100 degrees off (the worst
place for one garble); an Easycomm II at rest at 150 whose answers are off by 0, +60, -60 in turn
for a while (review 100's line), then sound.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from tests.engine.garblers import every_answer_off, frames_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 30.0, "el_speed_deg_s": 30.0}  # as review 100's fast rotor
ONE_GARBLE = [0.0, 0.0, 0.0, 100.0]  # the fourth frame off: seven unconfirmed, then one agrees
TURN_S = 60.0  # 290 degrees at 30 deg/s, with room (virtual time)
REST_DEG = 150.0
GARBLED_S = 5.0  # review 100's line: long enough for several stops (virtual time)
SOUND_S = 5.0  # the sound line's answers, several (virtual time)


def test_a_fast_turn_at_the_start_with_one_garbled_answer_is_not_stopped(rig: Rig) -> None:
    v = rig("rot2prog", emulator={"start_az_deg": 10.0, **FAST}, connect=False)
    v.manual_rotate(300.0)  # (turning when the bridge opens the port)
    v.run_for(0.5)  # (the turn under way: not a deadline)
    t = v.now
    v.to_host = frames_off(ONE_GARBLE)
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, TURN_S, "the turn ends")
    stops = [e.message for e in v.errors(since=t) if e.kind == ErrorKind.STOP]
    assert v.frames("stop", since=t) == [] and stops == [], stops
    assert v.truth().az_deg == 300.0
    assert v.status.available and v.status.bearing_deg is not None


def test_a_line_that_stops_garbling_is_confirmed_after_its_stops(rig: Rig) -> None:
    v = rig("easycomm2", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = every_answer_off([0.0, 60.0, -60.0])
    v.link_up()
    v.run_for(GARBLED_S)
    stopped = v.frames("stop")
    said = [e.message for e in v.errors() if e.kind == ErrorKind.STOP]
    assert len(stopped) > 1, stopped  # (again while they go on disagreeing)
    assert len(said) == 1 and "do not agree" in said[0], said  # (said once, not at each)
    assert not v.status.available and v.status.bearing_deg is None  # (nothing made of them)
    v.to_host = None
    v.run_for(SOUND_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG
    assert v.truth().az_deg == REST_DEG
