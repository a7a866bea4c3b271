"""Review 40: readings at rest that go on disagreeing (a failing position sensor, a line gone
bad) leave the bearing shown where the last two readings agreed (session/controller.py rule 9;
test_session_doubt.py's failing sensor). DOUBT_LOST_MOST was to bound answers given up *in a
row* to readings asked again (its words say so), but ``_Doubted.lost`` is carried from each
doubted reading to the next until a reading is taken, and a failing sensor's never are: one
reply in twenty lost on the line, spread over minutes, and the third such loss has the next
garbage reading taken, published as the bearing and followed as a turn (50, 250, 350 ...),
and again after each. Before attack 9's fix these readings were never shown."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.test_session_doubt import at_rest
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def failing_and_lossy(v: VirtualRotator, every: int) -> list[float]:
    """Every Rotor-EZ reply (``;ddd``) read with its hundreds digit 1 as 2, 3, 4 (junk) or 0 in
    turn (a failing sensor: 150 reads 250, 350, 450, 50 ...), and every ``every``-th reply lost
    on the line; returns the list the lost replies' instants go into."""
    lost: list[float] = []
    digits = iter(b"2340" * 100_000)
    count, drop, head = [0], [False], [False]

    def line(data: bytes, now: float) -> bytes:
        out = bytearray()
        for b in data:
            if b == ord(";"):
                count[0] += 1
                drop[0] = count[0] % every == 0
                head[0] = True
                if drop[0]:
                    lost.append(now)
                    continue
            elif drop[0]:
                continue
            elif head[0]:
                head[0] = False
                if b == ord("1"):
                    b = next(digits)
            out.append(b)
        return bytes(out)

    v.to_host = line
    return lost


@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_a_failing_sensor_on_a_line_that_loses_one_reply_in_twenty_is_never_believed(
    rig: Rig, model: str
) -> None:
    v = at_rest(rig, model)
    rest = v.status.bearing_deg
    t = v.now
    lost = failing_and_lossy(v, 20)
    v.run_for(200.0)
    assert len(lost) >= 3 * 3  # (DOUBT_LOST_MOST thrice over, each one reply in twenty)
    shown = [(round(s.bearing_deg or -1), s.state.value) for s in v.published(since=t)]
    assert v.status.bearing_deg == rest and {s for _, s in shown} <= {"idle"}, shown
    assert {b for b, _ in shown} <= {round(rest or -1), -1}, shown
