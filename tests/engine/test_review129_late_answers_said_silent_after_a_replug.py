"""Review 129: an RT-21 that answers every poll 0.62 s late (past the longest wait link.py rule
12 allows it, 0.6 s) is offline, told so with rule 12's words ('it answers, late: 0.64 s
after a poll ... a slow USB adapter or a serial server on the network?'). Its adapter
replugged, the next words are 'controller on ... does not answer', bare, 0.3 s into the new
connection, before its first answer could come: the silence carried across the replug
(ec5b8ce3, ``carry_silence``) has the new link's first question given up at the reply time
say it, and what the link before learned (the late answers) is not carried, so the words
that point at the adapter or the serial server are gone, and 'does not answer' points at
the cable or the power instead. At dd1e5dce the words after the replug still say it answers
late. A regression (words on R/error).

In virtual time: the emulated RT-21 at rest, its answers late from then on.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
SETTLE_S = 90  # for the first readings to be taken, at rest (virtual time)
LATE_S = 0.62  # each answer this late after its poll: past rule 12's longest wait (0.6 s)
OFFLINE_S = 20.0  # for the offline's words, with room (virtual time)
AFTER_S = 0.25  # the adapter pulled this long after them (virtual time)
DOWN_S = 0.5  # the worker's reconnect_min_s: the port reopened this much later (virtual time)
WATCH_S = 10.0  # the new connection's words, with room (virtual time)


def test_a_late_controller_is_still_said_late_after_a_replug(rig: Rig) -> None:
    v = rig("rt21", emulator={"start_az_deg": 20.0})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.answer_after(LATE_S)
    v.run_until(lambda h: bool(h.errors()) and "late" in h.errors()[-1].message, OFFLINE_S)
    v.run_for(AFTER_S)
    v.link_down("adapter reset")
    v.run_for(DOWN_S)
    t = v.now
    v.link_up()
    v.run_for(WATCH_S)
    said = [e.message for e in v.errors(since=t) if "answer" in e.message]
    assert said, "no words after the replug"
    assert all("late" in why for why in said), said  # observed: ['... does not answer']
