"""engine/link.py's slews: how long a silent controller's move may take, and how long its
report is waited for."""

from __future__ import annotations

import pytest

from bridge.engine.link import Link
from bridge.engine.slew import SLEW_MARGIN_S, SLEW_TIME_FACTOR, Slew
from bridge.protocols.satel import MODELS


@pytest.mark.parametrize(
    ("start", "to", "expected_s"),
    [
        ((10.0, 5.0), (100.0, 20.0), 15.0),  # az 90 deg at 6: 15 s; el 15 deg at 2.5: 6 s
        ((10.0, 5.0), (20.0, 80.0), 30.0),  # the elevation decides
        ((350.0, 0.0), (10.0, 0.0), 340 / 6),  # the long way: no wrap past the north stop
        ((None, None), (100.0, 20.0), 360 / 6),  # start unknown: whole spans
    ],
)
def test_travel_time_is_the_slower_axis(
    start: tuple[float | None, float | None], to: tuple[float, float], expected_s: float
) -> None:
    slew = Slew(0.0, *start, *to)
    assert slew.travel_s(6.0, 2.5, 360.0, 90.0) == pytest.approx(expected_s)


def test_a_slews_report_is_owed_until_its_bound_and_each_stop_brings_it_forward() -> None:
    spec = MODELS["satel"]
    link = Link(spec.codec_factory(), spec, 100.0, spec.baud)
    link.send(link.codec.encode_target(100, 20), 100.0)
    # no gap between `g` and `p`: both go at once, so a stop cannot fall between them and
    # cancel the point alone (the slew would be owed for a point never sent)
    assert b"".join(link.output()) == b"gp100 20\r\n" and link.frames_waiting == 0
    link.begin_slew(Slew(100.0, 10.0, 5.0, 100.0, 20.0), 15.0)
    assert link.reply_deadline == 100.0 + SLEW_TIME_FACTOR * 15.0 + SLEW_MARGIN_S == 135.0
    assert not link.reply_overdue(134.9) and link.reply_overdue(135.0)
    assert not link.free() and link.free(for_stop=True)  # only a stop may go into the slew
    for n, t in enumerate((120.0, 122.0), start=1):
        link.want_stop()
        assert link.flush_stop(t)  # a stop may go into a slew
        assert link.slew is not None and link.slew.stops == n
        assert link.reply_deadline == t + spec.reply_timeout_s
    assert b"".join(link.output()) == b"ss"
    link.give_up_reply(124.0)
    assert link.slew is None and link.reply_deadline is None and link.silent_for(124.5) == 0.5
