"""Review 104, of bdf3a473 (kept.py rule 13, state_store.py rule 15): a DCU-1's turn kept is
written to run out TURN_FILED_AHEAD_S past its hold, on the kernel's boot clock, and written
again only when a later target's end passes the end written, compared on the session's clock
(monotonic). The two clocks part at a suspend: CLOCK_BOOTTIME counts the machine's sleep,
CLOCK_MONOTONIC does not. A laptop at a portable station that sleeps while a turn is kept
(within a range's slow time and a minute of the last target) and is woken for the next target
within ten minutes (on the session's clock) of the last: that target writes nothing, as the
end written looks later, while on the boot clock that end is long past. The bridge killed
mid-turn (a crash) and started again reads the file as at rest: a follow start refused at
once halts nothing, and the DCU-1 turns on to the old target under "refused" (review 89's
case, the unsafe side kept.py rule 13 was written against)."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.core.model import ErrorKind
from tests.engine.test_attack19_follow_start_refused_grid import PARTNER
from tests.engine.test_review93_dcu1_turn_kept_in_the_state_file import Filed, filed_dcu1
from tests.integration.test_pointing_bridge import angle_between

SLEPT_S = 3600.0  # the machine suspended for an hour


class Slept(Filed):
    """Filed, on a machine that was suspended: its boot clock counts the sleep, the session's
    (virtual, monotonic) clock does not."""

    slept_s = 0.0

    def boot(self) -> tuple[str, float]:
        boot_id, now = super().boot()
        return boot_id, now + self.slept_s


def test_a_dcu1_turn_sent_after_a_suspend_is_kept_and_a_refused_start_stops_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with filed_dcu1(tmp_path, monkeypatch) as plain:
        v = plain.v
        f = Slept(plain.path, v, monkeypatch)
        v.target(round(PARTNER + 60.0))  # a turn of the bridge's (file: a turn kept)
        v.run_for(30.0)  # (the turn over, its hold not: not a deadline)
        f.feed()
        assert f.says_turn()
        f.slept_s = SLEPT_S  # the laptop sleeps an hour, the rotor at rest; woken, the next
        v.target(round(PARTNER + 140.0))  # target, 80 degrees on: the DCU-1 turns by itself
        v.run_until(lambda h: h.truth().is_moving, 60, "the turn under way")
        v.run_for(5.0)  # (some 30 degrees on: not a deadline)
        f.feed()
        assert v.truth().is_moving
        f.restarted()  # the bridge killed mid-turn and started again from its file
        assert v.truth().is_moving  # (the DCU-1 finishes its turn by itself)
        t, here = v.now, v.truth().az_deg
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the old target is some 20 s on: not a deadline)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        assert "stop" in {fr.outcome for fr in v.frames(since=t)}
        assert angle_between(v.truth().az_deg, here) <= 15.0, (here, v.truth().az_deg)
