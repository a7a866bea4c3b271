"""Review 131: an operator's STOP to a controller a torn line keeps offline at rest goes out
seconds late when an unwatched stop was written just before the rotor began to turn: the STOP is
taken for one that adds nothing, and the rotor runs on until the next unwatched stop by the clock
(2.5 to 3.5 s later, 15 degrees and more at the box's speed). The parent writes it at once.

Commit 6f997233 (controller.py rule 9, ``_offline_phase``) writes the unwatched stop while such a
controller is offline at rest, the eighth torn answer and then every UNWATCHED_TURN_DEG at its
speed. Stops.py rule 1 merges a stop into one written a brake window before (nothing it could
add, as far as the readings show: none come from this line). Review 116 kept the unwatched stop
itself from being merged away for the same reason; an operator's STOP right after one is. A
STOP must always get through: here the controller hears every frame, and the STOP is the only
thing between a turning rotor and its end. (The same merge is older than this commit in review
116's few seconds while the controller still answers at rest: there the parent never writes the
STOP at all; this commit brings it to the whole time such a controller is offline, where the
parent, having written no stop, writes the STOP at once.)

In virtual time: the emulated box at rest at 150, confirmed on a clean line; then every byte it
sends XORed with 0x5A; once it is offline, right after an unwatched stop went (where one goes:
the parent writes none), a hand at the panel turns it towards 300, and half a second later the
operator sends STOP.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import confirmed_at_rest
from tests.engine.test_review113_every_byte_garbled_unwatched import torn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 100.0
CONFIRMED_S = 15.0  # the start's readings on a clean line (virtual time, not a deadline)
GOING_OFFLINE_S = 30.0  # two silence timeouts, with room (virtual time)
OFFLINE_STOP_S = 10.0  # the next unwatched stop offline comes within this, if any (virtual time)
STEP_S = 0.01  # a step of virtual time to catch that stop as it goes: not a deadline
HAND_S = 0.5  # the hand's turn under way when the operator sends STOP (virtual time)
AFTER_S = 6.0  # watched after the STOP, past the next unwatched stop (virtual time)
STOP_WITHIN_S = 0.3  # the STOP's frame on the wire after it was sent, at most (virtual time)


@pytest.mark.parametrize(
    "model",
    [
        ("gs232b"),
        ("rt21"),
        ("easycomm2"),
        ("rc2800-az"),
    ],
)
def test_an_operators_stop_right_after_an_offline_unwatched_stop_goes_at_once(
    rig: Rig, model: str
) -> None:
    v = confirmed_at_rest(rig, model, REST_DEG, AZ_MIN_DEG, CONFIRMED_S)
    v.to_host = torn
    v.run_until(lambda h: not h.status.available, GOING_OFFLINE_S, "the offline")
    t0 = v.now
    while v.now < t0 + OFFLINE_STOP_S and not v.frames("stop", since=t0):
        v.run_for(STEP_S)  # (right after an unwatched stop offline, where one goes)
    v.manual_rotate(300.0)  # (a hand at the panel)
    v.run_for(HAND_S)
    assert v.truth().is_moving  # (the premise: it turns when the STOP is sent)
    t = v.now
    v.stop()
    v.run_for(AFTER_S)
    stops = [round(f.time_s - t, 2) for f in v.frames("stop", since=t)]
    assert stops and stops[0] <= STOP_WITHIN_S, (
        f"{model}: the operator's STOP reached the controller {stops} s after it was sent; "
        f"the rotor ran from {REST_DEG:g} to {v.truth().az_deg:.1f}"
    )
