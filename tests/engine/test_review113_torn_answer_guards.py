"""Review 113's fix (link.py rule 11: an answer torn past any form is garbled) counts only
answers that never form a reply: a controller whose answers are still arriving when their
reply time passes (in parts, late) forms its reply with the rest, and its turn at the start is
followed, neither stopped as unwatched (controller.py rule 9) nor told as garbled. Counting
the first torn answer of a run alone (not the second in a row, no reply formed between) tells
the answers in parts as garbled: each one's head is most of it, and its rest forms the line
only after it was given up.

In virtual time: review 107's start (the emulated Easycomm II box turning from 150 to 300 when
the bridge starts); every answer comes in two parts, the second GAP_S after the first, across
its reply time, or starts late.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 150.0
END_DEG = 300.0
TURNING_S = 0.5  # the turn under way when the bridge starts (virtual time, not a deadline)
WATCH_S = 20.0  # the turn, 25 s at 6 deg/s, well under way (virtual time)
HEAD_BYTES = 10  # of each answer, before the pause: most of it
GAP_S = 0.8  # the pause within each answer: past the longest wait, twice its 0.4 s reply time
LATE_S = 0.5  # each answer starts this late: past its 0.4 s reply time (virtual time)


def in_parts(v: VirtualRotator) -> Callable[[bytes, float], bytes]:
    """Each answer's first HEAD_BYTES, then the rest GAP_S later (held on the line)."""
    seen = [0]

    def split(data: bytes, now: float) -> bytes:
        for byte in data:  # (the emulator's output comes byte by byte)
            seen[0] += 1
            if seen[0] == HEAD_BYTES + 1:
                v.delay_output(GAP_S)
            if byte == ord("\n"):
                seen[0] = 0
        return data

    return split


@pytest.mark.parametrize("how", ["in parts", "late"])
def test_answers_still_arriving_are_not_counted_torn(rig: Rig, how: str) -> None:
    v = rig(
        "easycomm2",
        emulator={"start_az_deg": START_DEG},
        settings={"unasked_moves": "follow"},  # (rule 10 lets it be: rule 9 alone judged)
        connect=False,
    )
    v.device.receive(f"AZ{END_DEG:.1f} EL0.0\n".encode(), v.now)  # (turning at the start)
    v.run_for(TURNING_S)
    assert v.truth().is_moving
    t = v.now
    if how == "late":
        v.answer_after(LATE_S)
    else:
        v.to_host = in_parts(v)
    v.link_up()
    v.run_for(WATCH_S)
    said = [e.message for e in v.errors(since=t)]
    assert not v.frames("stop", since=t), f"the turn was stopped; said: {said}"
    assert not [s for s in said if "garbled" in s], said
