"""Review 131: a stop the unwatched count wrote while a torn line kept the controller offline at
rest stays checked after the line comes right: a hand at the panel half a minute later (or five
minutes later) is stopped at its first reading, unsaid (the log: "still turning after a stop;
stopping again"), on a Rotor-EZ, a RotorCard, an RT-21, a Prosistel, an MD-01 and a Rot1Prog
(a GS-232A/B's are let go).

Commit 6f997233 (controller.py rule 9, ``_offline_phase``) counts answers garbled past parsing
toward the unwatched stop once they took the controller offline at rest, and writes those stops
while it is offline. Rule 9 promises such a stop is "checked only until a reading a resend time
after it shows the rotor still, then let go as a released lock's stop" (review 107: "a hand at the
panel ten minutes after the line came right was stopped, unsaid"). The ones written offline are
not let go: the readings back show the rotor still for a minute, and still the first move by hand
gets a stop. Seen in the controller: the unwatched stop before the offline was owed again "when
it answers" as a let-go one (``_released_owed``); each stop written offline (``stop``) sets that
False, so the copy written when it answers is checked as an operator's, for good (review 113's
defect back). A GS-232A/B, offline before its eighth, owes none. The parent (befd8583) wrote none
offline and follows the hand.

In virtual time: the emulated box at rest at 150 (``az_min_deg`` 100), confirmed on a clean
line; every byte it sends XORed with 0x5A until it has been offline OFFLINE_S; then a clean line
again, the controller answering; BACK_S later a hand at the panel turns it to 220, inside the
limits, with no lock and no target out.
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
HAND_DEG = 220.0
CONFIRMED_S = 15.0  # the start's readings on a clean line (virtual time, not a deadline)
GOING_OFFLINE_S = 30.0  # two silence timeouts, with room (virtual time)
OFFLINE_S = 40.0  # offline at rest on the torn line, its stops written (virtual time)
COMING_BACK_S = 30.0  # the clean line's first readings taken (virtual time)
BACK_S = 30.0  # answering at rest, the stops' check long over (virtual time)
HAND_S = 40.0  # the hand's turn, on its way to HAND_DEG at the box's speed (virtual time)
TURNED_DEG = 30.0  # how far the hand turns it by then at the slowest box's speed, at least


@pytest.mark.parametrize(
    "model",
    [
        ("rotorez"),
        ("rotorcard"),
        ("rt21"),
        ("prosistel"),
        ("md01"),
        ("rot1prog"),
        "gs232b",  # (followed: its stops written offline are let go)
        "gs232a",
    ],
)
def test_a_hand_turn_after_the_torn_line_came_right_is_followed_not_stopped(
    rig: Rig, model: str
) -> None:
    v = confirmed_at_rest(rig, model, REST_DEG, AZ_MIN_DEG, CONFIRMED_S)
    torn_t = v.now
    v.to_host = torn
    v.run_until(lambda h: not h.status.available, GOING_OFFLINE_S, "the offline")
    v.run_for(OFFLINE_S)
    assert v.sent(since=torn_t)  # (the premise: the bridge went on writing to it)
    v.to_host = None  # (the line comes right)
    v.run_until(lambda h: h.status.available, COMING_BACK_S, "answering again")
    v.run_for(BACK_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG  # (watched again, at rest)
    t = v.now
    v.manual_rotate(HAND_DEG)  # (a hand at the panel, inside the limits)
    v.run_for(HAND_S)
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    said = [e.message for e in v.errors(since=t)]
    assert stops == [] and v.truth().az_deg >= REST_DEG + TURNED_DEG, (
        f"{model}: a hand turn to {HAND_DEG:g} stopped at {v.truth().az_deg:g}, stops written "
        f"{stops} s into it; said: {said}"
    )
