"""Review 33: status.py rule 1 after 124cf91b. A rotor whose travel ends at north, shown at
10, is sent up the scale to 300; the bridge's process held through the turn, it is next read
at 301, past its target (it coasts on), then found still at 302. The jump of more than half a
turn now takes its way "on from the reading to the target": 300 - 301, down, though it went up
from 10 (the way from the bearing shown before can be told here: 10 is not the scale's end).
Its last degree, 302, a step up while it comes to rest, is then taken for jitter against that
way and not shown: the rotor at 302 is shown at 301 for good (rule 1: the last degrees of a
turn are the bearing it ends at). Before 124cf91b (the way from 10 to the target, up) 302 was
shown; a step back at rest, 301.5, would now be shown as the turn's last degree instead."""

from __future__ import annotations

from bridge.session.status import Hysteresis


def test_a_turn_up_read_late_past_its_target_shows_its_last_degree() -> None:
    shown = Hysteresis()
    shown.feed(10, False, 2, True, False)  # at rest at 10
    shown.feed(301, True, 2, True, False, toward=300)  # read late: 1 past its target, coasting
    shown.feed(302, False, 2, True, True, toward=300)  # found still: its last degree
    assert shown.value == 302
