"""Review 97 (Medium), of 6311424a (kept.py rule 13, state_store.py rule 15): the state file
keeps a DCU-1's turn as a bare ``turn_kept: true``, with no time, and only a running bridge
clears it (TURN_KEPT_S past the turn's end). A bridge that ends within that minute (the
operator turns the antenna, or parks it, and shuts the station down; a crash; a power cut)
leaves it true for good: the next start, an hour or a day later, takes the DCU-1 as finishing
a turn long over, and a follow start refused at once stops the operator's own turn at the
panel, as review 93 found every start did. The rule says "one restarted within TURN_KEPT_S of
a turn's end" stops a hand at a refused start; this one was restarted an hour after it."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.core.model import ErrorKind
from bridge.session import motion as mo
from bridge.session.session import RotatorSession
from tests.engine.test_attack19_follow_start_refused_grid import (
    PARTNER,
    turning_away_from_the_partner,
)
from tests.engine.test_review93_dcu1_turn_kept_in_the_state_file import filed_dcu1
from tests.integration.test_pointing_bridge import angle_between

DOWN_S = 3600.0  # the station off for an hour


def test_a_dcu1_turn_over_an_hour_before_the_start_does_not_stop_a_hand_at_a_refused_start(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with filed_dcu1(tmp_path, monkeypatch) as f:
        v = f.v
        motion = v.cfg.motion
        turning_away_from_the_partner(v)  # the bridge's last turn, to 182
        # (its end, assumed for the whole range, and 10 s of the hold after it: not a deadline)
        v.run_for(mo.blind_busy_s(motion.az_span_deg, motion) + 10.0)
        assert not v.truth().is_moving  # over, and the bridge takes it so
        f.feed()
        assert f.says_turn()  # (within the minute's hold: the file says a turn)
        v.link_down(None)  # the bridge ends here, and the station is off for an hour
        v.run_for(DOWN_S)  # (the bridge down: not a deadline)
        v.session = RotatorSession(v.cfg, turn_kept=f.says_turn())
        v._do(v.session.start(v.now))
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers the new bridge")
        to = round(PARTNER + 260.0)  # (302: off the keep-out sector, never through it)
        v.manual_rotate(to)  # the operator turns it on the front panel
        v.run_for(2.0)  # (the hand's turn under way: not a deadline)
        assert v.truth().is_moving
        t = v.now
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the hand's turn some 20 s on: not a deadline)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        assert "stop" not in {fr.outcome for fr in v.frames(since=t)}
        assert angle_between(v.truth().az_deg, to) <= 2.0, (to, v.truth().az_deg)


def test_a_dcu1_turn_kept_at_a_reboot_is_still_kept_and_a_refused_start_stops_the_rotor(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The fix's safe side (state_store.py rule 15): the boot clock of another boot says
    nothing of how long the machine was down, so a turn kept when the bridge ended is kept at
    a start on another boot, and a follow start refused at once stops the DCU-1 (a hand's
    turn at the panel too: the price, as before review 93's fix)."""
    with filed_dcu1(tmp_path, monkeypatch) as f:
        v = f.v
        motion = v.cfg.motion
        turning_away_from_the_partner(v)
        v.run_for(mo.blind_busy_s(motion.az_span_deg, motion) + 10.0)  # (not a deadline)
        f.feed()
        assert f.says_turn()
        v.link_down(None)  # the bridge ends within the hold; the machine reboots
        v.run_for(DOWN_S)  # (the bridge down: not a deadline)
        f.rebooted()
        v.session = RotatorSession(v.cfg, turn_kept=f.says_turn())
        v._do(v.session.start(v.now))
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers the new bridge")
        v.manual_rotate(round(PARTNER + 260.0))  # the operator turns it on the front panel
        v.run_for(2.0)  # (the hand's turn under way: not a deadline)
        t, here = v.now, v.truth().az_deg
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the hand's turn some 20 s on: not a deadline)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        assert "stop" in {fr.outcome for fr in v.frames(since=t)}
        assert angle_between(v.truth().az_deg, here) <= 15.0, (here, v.truth().az_deg)


def test_a_stream_of_targets_past_ten_minutes_keeps_the_files_end_ahead_of_the_last_turn(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """kept.py rule 13: the file's end is written TURN_FILED_AHEAD_S past the hold's and again
    when a later target's passes it: 80 targets 10 s apart write it twice, and a bridge
    killed after the last still finds the turn kept till that one's hold is nearly over."""
    with filed_dcu1(tmp_path, monkeypatch) as f:
        v = f.v
        motion = v.cfg.motion
        f.feed()
        before = f.writes
        bearing = round(PARTNER + 40.0)
        for n in range(80):
            v.target(bearing + (n % 30))
            v.run_for(10.0)  # (the next target's time: not a deadline)
            f.feed()
            assert f.says_turn(), n
        assert f.writes - before == 2, f"{f.writes - before} state file writes"
        v.link_down(None)  # the bridge killed 10 s after its last target
        whole = mo.blind_busy_s(motion.az_span_deg, motion)
        v.run_for(whole + mo.TURN_KEPT_S - 15.0)  # (5 s short of its hold's end)
        assert f.says_turn()
