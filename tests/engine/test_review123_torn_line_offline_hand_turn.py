"""Review 123: once a line that garbles every byte has taken a rotor at rest offline ('answers
only garbled replies'), a hand turn is never stopped: it runs from 150 past ``az_min_deg`` 100 to
its end, no stop frame written, though the controller hears every frame the bridge writes.

controller.py rule 9 (review 116's third fix, 40a3ae59): answers garbled past parsing at rest
count toward the unwatched stop, "the limits hold over a rotor the bridge cannot watch" (the
team's decision). But they count only while it is answering (``_rest_phase``), and rule 2 takes a
controller whose answers are all garbled offline after two silence timeouts (6 s): from then on
nothing counts, nothing is stopped. The offline's words promise "The last stop, no reading showed
taking, goes again when it answers": on a line that goes on garbling it never answers. An
Easycomm II on that line gets one unwatched stop at the moving rate, then goes offline; a hand at
the panel 30 s later turns it from 150 to 5 unstopped, polled all the while (its answers come,
garbled). Readings that parse and disagree are kept online (rule 9, "the first back, doubted, is
an answer all the same") and stopped again and again; bytes that parse as nothing are not.

In virtual time: the emulated Easycomm II box at rest at 150 (``az_min_deg`` 100), confirmed on
a clean line; then every byte it sends reaches the host XORed with 0x5A (review 113's ``torn``);
once it is offline, and a while on, a hand turns the rotor down to 5 at the box's speed.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import confirmed_at_rest, lowest_az
from tests.engine.test_review113_every_byte_garbled_unwatched import torn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 100.0
CONFIRMED_S = 15.0  # the start's readings on a clean line (virtual time, not a deadline)
OFFLINE_S = 30.0  # two silence timeouts, with room (virtual time)
HAND_AFTER_S = 30.0  # the hand comes this long after the offline (virtual time)
WATCH_S = 60.0  # 145 degrees at 6 deg/s, with room (virtual time)


@pytest.mark.xfail(
    strict=True,
    reason="review 123: a rotor at rest taken offline by a line garbling every byte is never "
    "stopped again: a hand turn runs past az_min_deg to its end",
)
def test_a_hand_turn_after_a_torn_line_took_it_offline_is_stopped_before_the_limit(
    rig: Rig,
) -> None:
    v = confirmed_at_rest(rig, "easycomm2", REST_DEG, AZ_MIN_DEG, CONFIRMED_S)
    v.to_host = torn
    v.run_until(lambda h: not h.status.available, OFFLINE_S, "the offline")
    v.run_for(HAND_AFTER_S)
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG)
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    polls = len(v.sent(since=t))
    assert polls  # (the premise: the bridge goes on writing to it)
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; {polls} frames written meanwhile, stops {stops} s into the turn"
    )
