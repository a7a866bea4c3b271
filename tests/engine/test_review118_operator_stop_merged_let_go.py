"""Review 118: an operator's STOP pressed just after controller.py rule 9's unwatched stop is
merged into it (stops.py rule 1: within the brake window, nothing more on the wire) and then
let go as the unwatched stop (``_release_check``: ``stop_sent_t`` is still the unwatched
stop's, ``_released_stop_t``): the check stops.py rule 2 keeps on an operator's STOP to a
rotor the bridge took for at rest ("checked too, until the next target ... the price: a move
by hand long after such a stop is stopped once too"; the unwatched stop alone is let go
because "nobody pressed STOP") is lost. Somebody did press STOP: a hand at the panel ten
minutes later is followed, not stopped.

Review 113's ``_let_go`` (commit 83c183bb) now does the same across a drop: the port failing
just after that STOP owes the stop (stops.py rule 3) and marks it released because its
``unseen_t`` is the unwatched stop's; the parent wrote it on the reconnect as an operator's,
checked (the hand turn stopped 0.77 s in). On one connection the parent lets it go too.

In virtual time: review 107's start (the emulated GS-232B at rest at 150, readings of a
failing sensor that never agree) until the unwatched stop is written; the operator's STOP at
once; the line sound from then (in the "drop" case the port fails then and is back DOWN_S
later); ten minutes on, a hand turns the rotor to 250.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.session.stops import STOP_MERGE_MIN_S
from tests.engine.garblers import every_frame_off
from tests.engine.test_review105_first_readings_polled_at_the_moving_rate_forever import failing
from tests.engine.test_review107_unwatched_stop_checked_for_good import (
    HAND_DEG,
    REST_DEG,
    hand_turn_after,
)
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
GARBLED_S = 10.0  # for the unwatched stop to be written (virtual time)
DOWN_S = 1.0  # the drop (virtual time, not a deadline)
ROT2PROG_GARBLED_S = 60.0  # a Rot2Prog's first unwatched stop, and a poll out (virtual time)
OFFSETS = [0.0, 60.0, -60.0]  # review 111's line: every position frame off in turn


@pytest.mark.parametrize("drop", [False, True], ids=["live", "across a drop"])
def test_an_operators_stop_merged_into_the_unwatched_stop_stays_checked(
    rig: Rig, drop: bool
) -> None:
    v = rig("gs232b", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = failing()
    v.link_up()
    v.run_until(lambda h: h.frames("stop"), GARBLED_S, "the unwatched stop written")
    written = len(v.frames("stop"))
    v.stop()  # (the operator: merged into it, stops.py rule 1)
    v.to_host = None
    if drop:
        v.link_down()  # (within STOP_UNSURE_S of the stop: it is owed)
        v.run_for(DOWN_S)
        v.link_up()
    else:
        v.run_for(DOWN_S)
        assert len(v.frames("stop")) == written  # (the premise: merged, nothing more written)
    stops, said = hand_turn_after(v)
    assert stops, (
        f"the hand turn after the operator's STOP, {REST_DEG:g} to {HAND_DEG:g}, went unstopped to "
        f"{v.truth().az_deg:g}; said: {said}"
    )


def test_an_operators_stop_waiting_on_a_half_duplex_line_stays_checked_across_a_drop(
    rig: Rig,
) -> None:
    """The half-duplex form (review 118's suspicion): on a Rot2Prog an operator's STOP, pressed
    past the unwatched stop's brake window while a poll's reply is in flight, waits for the
    line (link.py rule 3); the port fails then. It is owed (stops.py rule 3), and ``_let_go``
    read the last stop written, the unwatched one: the operator's was written on the
    reconnect as released, and a hand turn ten minutes later went unstopped."""
    v = rig("rot2prog", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = every_frame_off(OFFSETS)
    v.link_up()
    v.run_until(lambda h: h.frames("stop"), ROT2PROG_GARBLED_S, "the unwatched stop written")
    ctl = v.session.controller
    v.run_for(max(ctl.cfg.motion.brake_delay_s, STOP_MERGE_MIN_S))  # (stops.py rule 1's merge)
    v.run_until(
        lambda h: ctl.link is not None and ctl.link.reply_owed, ROT2PROG_GARBLED_S, "a poll out"
    )
    written = len(v.frames("stop"))
    v.stop()  # (the operator: it waits for the reply in flight)
    assert ctl.link is not None and ctl.link.stop_due  # (the premise)
    v.to_host = None
    v.link_down()
    v.run_for(DOWN_S)
    v.link_up()
    v.run_until(lambda h: len(h.frames("stop")) > written, DOWN_S, "the owed stop written")
    stops, said = hand_turn_after(v)
    assert stops, (
        f"the hand turn after the operator's STOP, {REST_DEG:g} to {HAND_DEG:g}, went unstopped to "
        f"{v.truth().az_deg:g}; said: {said}"
    )
