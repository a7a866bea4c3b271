"""Attack 22: a SatEL's connect writes its set-up right behind its stop, so a stop lost on the
line lets all of it into a slew the box was still running, and the box is wedged.

protocols/satel.py rule 2 begins the connect with ``s`` because the bridge "may have been
restarted in the middle of a slew it knows nothing about"; the fact sheet (satel.md section 6):
"never send anything between ``p...`` and the end of its status report", the controller "can
be put into a bad state by sending commands while it is slewing". In a slew the bridge keeps
that: a stop is followed by the report within one reply time or written again, and only then
is the controller asked anything (session/slew.py rule 6: "a stop byte lost on the line must
not let the poll that follows into a slew"). At connect it does not: ``s x ? t... g z`` go out
in one breath. One noise burst on the ``s`` and the ``x`` is input while slewing: a box that
takes it as the sheet warns (the emulator's ``corrupt_on_misuse``, rule 7) halts where it is
with motion off and ignores ``g`` and ``p`` until a reset, which the bridge never sends. The
status shows it idle with no error; the next target is given up a minute later.

In virtual time (tests/engine/virtual.py); the earlier process's slew is the box's own input.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.virtual import VirtualRotator, settled_at

Rig = Callable[..., VirtualRotator]


def test_a_connect_whose_stop_is_lost_sends_nothing_more_into_the_slew(rig: Rig) -> None:
    v = rig("satel", connect=False, emulator={"corrupt_on_misuse": True})
    v.device.receive(b"g", v.now)  # the process before this one set the box slewing
    v.device.receive(b"p200 60\r\n", v.now)
    v.run_for(2)  # (the bridge restarts mid-slew: not a deadline)
    assert v.truth().slewing
    v.drop_writes(b"s")  # one noise burst on the connect's stop
    v.link_up()
    v.run_for(5)  # (the connect's exchanges: not a deadline)
    assert v.truth().misuse_count == 0, [f for f in v.device.log if "misuse" in f.outcome][:3]
    v.target(100, 30)
    v.run_until(settled_at(100, 30), 120, "at 100/30")
