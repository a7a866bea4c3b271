"""Review 116: a line that tears every answer at rest (no value parses) gets no unwatched stop:
a hand turn then runs from 150 past ``az_min_deg`` 60 to its end, no stop written.

controller.py rule 9 (review 103's follow-up, f23b2118; the team's decision: "the limits hold over
a rotor the bridge cannot watch") stops a rotor at rest whose readings go on disagreeing, as a
connection's first readings are stopped. For first readings "a poll answered garbled past
parsing counts as one" (review 107: a line that tore every answer had none counted, and a turn at
the start ran past ``az_min_deg`` to its end; ``_garbled_first``). At rest nothing counts such
answers: only readings that parse and disagree reach the count. On a line that tears each
answer's decimal point the bridge says the controller "answers only garbled replies", and a hand
at the panel turns the Easycomm, which a clean line stops a second in (rule 10, at
about 144), from 150 past ``az_min_deg`` 60 down to 5. The parent did the same: f23b2118 extends
the unwatched stop to readings at rest, and leaves out review 107's half of it.

In virtual time: the emulated Easycomm II box at rest at 150 (``az_min_deg`` 60), confirmed on a
clean line; then every ``.`` it sends reaches the host as ``?``, and a hand turns the rotor down
to 5 at the box's speed.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import confirmed_at_rest, lowest_az
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 60.0
CONFIRMED_S = 10.0  # the start's readings on a clean line (virtual time, not a deadline)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)


def torn(data: bytes, now: float) -> bytes:
    """Each answer's decimal points garbled: no value parses."""
    return data.replace(b".", b"?")


def test_a_hand_turn_at_rest_on_a_torn_line_is_stopped_before_the_limit(rig: Rig) -> None:
    v = confirmed_at_rest(rig, "easycomm2", REST_DEG, AZ_MIN_DEG, CONFIRMED_S)
    v.to_host = torn
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG)
    said = [e.message for e in v.errors(since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stop frames: {len(v.frames('stop', since=t))}; said: {said}"
    )


HEALTHY_S = 120.0  # two minutes at rest (virtual time)
TEAR_EVERY = 5  # one answer torn in this many, the rest clean


def test_one_torn_answer_now_and_then_at_rest_gets_no_stop(rig: Rig) -> None:
    """The guard: a healthy box at rest whose line tears one answer in five (one garble is
    never eight in a row) is not stopped, and its bearing stands."""
    v = confirmed_at_rest(rig, "easycomm2", REST_DEG, AZ_MIN_DEG, CONFIRMED_S)
    answers = [0]

    def now_and_then(data: bytes, now: float) -> bytes:
        out = bytearray()
        for b in data:
            if b == ord("\n"):
                answers[0] += 1
            out.append(ord("?") if b == ord(".") and answers[0] % TEAR_EVERY == 0 else b)
        return bytes(out)

    v.to_host = now_and_then
    t = v.now
    v.run_for(HEALTHY_S)
    assert answers[0] > 2 * TEAR_EVERY  # (the premise: answers came, some of them torn)
    assert not v.frames("stop", since=t), [e.message for e in v.errors(since=t)]
    assert v.status.available and v.status.bearing_deg == REST_DEG
