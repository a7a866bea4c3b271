"""Review 129: a SatEL whose answers were lost for SILENT_S (9 s, short of its silence time, 9.8 s:
not yet offline), its adapter then replugged and the line good again, is told 'controller on
... does not answer' 1.15 s into the new connection, as its first answer is arriving (its
connect's stops, 0.38 s apart, then its questions), and is shown online 0.4 s later. Since
ec5b8ce3 the silence goes on across a replug (``carry_silence``), and the 'never answered'
path of controller.py rule 2 fires at the carried silence's end wherever the connect has got
to, with none of rule 2's verdict (a question whose answer decides): the words say the
controller is gone as it answers. At dd1e5dce nothing is said. A regression (words on
R/error).

In virtual time: the emulated SatEL at rest.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
SETTLE_S = 90  # for the first readings to be taken, at rest (virtual time)
SILENT_S = 9.0  # its answers lost this long: short of its silence time (virtual time)
DOWN_S = 0.5  # the worker's reconnect_min_s: the port reopened this much later (virtual time)
WATCH_S = 10.0  # the new connection's connect and readings, with room (virtual time)


def test_a_satel_answering_after_a_replug_is_not_said_silent(rig: Rig) -> None:
    v = rig("satel", emulator={"start_az_deg": 20.0})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.set_silent(True)
    v.run_for(SILENT_S)
    assert v.status.available  # (not yet offline)
    v.link_down("adapter reset")
    v.run_for(DOWN_S)
    v.set_silent(False)
    t = v.now
    v.link_up()
    v.run_for(WATCH_S)
    assert v.status.available and v.status.bearing_deg == 20.0  # (it answers)
    said = [e.message for e in v.errors(since=t) if "answer" in e.message]
    assert said == [], said  # observed: ['controller on /dev/ttyVIRTUAL does not answer']
