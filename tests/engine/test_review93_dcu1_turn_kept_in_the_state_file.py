"""Review 93 (Medium), the fix: a DCU-1 reports no position, so a bridge just started cannot
tell the old bridge's turn from a hand's at the panel; the state file says whether the run
before may have left a turn of its own in flight (runtime/kept.py rule 13, session/motion.py
rule 6 ``turn_kept``). These run the session's statuses through the rotator's Kept into a
real state file on disk, and start the next session from what a new store reads back."""

from __future__ import annotations

import json
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from bridge.core.model import ErrorKind
from bridge.runtime.kept import Kept
from bridge.runtime.state_store import StateStore
from bridge.session import motion as mo
from bridge.session.session import RotatorSession
from tests.engine.test_attack19_follow_start_refused_grid import (
    PARTNER,
    follower_by_a_keep_out,
    turning_away_from_the_partner,
)
from tests.engine.test_review73_dcu1_refused_start_after_replug import (
    a_dcu1s_refused_follow_start_holds_the_rotor,
)
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between

BOOT = "0f5e0c3a-97b1-4c1e-9d2a-3b6c2f4e8a11"  # the machine's boot id, as the kernel's reads


class Filed:
    """The rotator's Kept on a real state file, fed every status the session published (as
    runtime/rotator.py ``_status`` does on the lines thread), its file writes counted. The
    machine's boot clock (state_store.py rule 15) is the virtual one, some hours on: no boot
    of the machine's between the runs (``rebooted`` for one)."""

    def __init__(self, path: Path, v: VirtualRotator, monkeypatch: pytest.MonkeyPatch) -> None:
        self.path, self.v, self.writes, self._fed = path, v, 0, 0
        self.boot_id = BOOT
        self.store = StateStore(path, boot=self.boot)

        def report(kind: ErrorKind, message: str, what: str | None) -> None:
            raise AssertionError(message)

        self.kept = Kept(
            self.store, v.cfg.rotator_id, v.cfg.spec, report=report, clock=lambda: v.now
        )
        real = StateStore._write

        def counted(store: StateStore, at: Path, *, put_in_place: bool = True) -> None:
            self.writes += 1
            real(store, at, put_in_place=put_in_place)

        monkeypatch.setattr(StateStore, "_write", counted)

    def boot(self) -> tuple[str, float]:
        """The boot id and CLOCK_BOOTTIME now, on the virtual clock (12 h since the boot)."""
        return self.boot_id, 43200.0 + self.v.now

    def rebooted(self) -> None:
        """The machine started again: another boot id, its clock counted anew."""
        self.boot_id = f"{self.boot_id}-again"

    def feed(self) -> None:
        """The statuses published since the last feed, in order, and their saves written
        (each on the writer thread: the clocks read there at the status's time, a step
        behind at most)."""
        for _t, status in self.v.statuses[self._fed :]:
            self.kept.seen_turn(status.turn_kept, status.turn_kept_until)
        self._fed = len(self.v.statuses)
        self.store.flush()

    def says_turn(self) -> bool:
        """What the file on disk says, read as the next start reads it."""
        return StateStore(self.path, boot=self.boot).turn_kept(self.v.cfg.rotator_id)

    def restarted(self) -> None:
        """The bridge killed where it stands (a crash, SIGKILL: no stop at its end) and started
        again, from what its state file says."""
        self.feed()
        v = self.v
        v.link_down(None)
        v.run_for(1.0)  # (the bridge down: not a deadline)
        kept = self.says_turn()
        v.session = RotatorSession(v.cfg, turn_kept=kept)
        v._do(v.session.start(v.now))
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers the new bridge")


@contextmanager
def filed_dcu1(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Filed]:
    with follower_by_a_keep_out("dcu1") as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        yield Filed(tmp_path / "state.json", v, monkeypatch)


def test_a_dcu1_restarted_mid_turn_is_halted_by_a_refused_start_from_what_its_file_kept(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Review 89's case through the state file: the turn sent is kept, the bridge killed mid-
    turn, and the next start's refused follow start holds the rotor where it was."""

    def killed_mid_turn(v: VirtualRotator) -> None:
        f = Filed(tmp_path / "state.json", v, monkeypatch)  # (fed every status since start)
        f.feed()
        assert f.says_turn()  # (written at the turn's start: review 89's turn is kept)
        f.restarted()
        assert v.truth().is_moving  # (it finishes its old turn by itself)

    a_dcu1s_refused_follow_start_holds_the_rotor(killed_mid_turn)


def test_a_dcu1_whose_turn_was_stopped_is_at_rest_at_the_next_start_and_a_hand_goes_on(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A run that sent a turn and stopped it leaves the file at rest: after a restart, a hand
    at the panel is not stopped by a refused follow start (review 93's hand, after a run with
    a turn of its own, not only after a fresh file)."""
    with filed_dcu1(tmp_path, monkeypatch) as f:
        v = f.v
        turning_away_from_the_partner(v)
        f.feed()
        assert f.says_turn()
        v.stop()
        v.run_for(mo.TURN_KEPT_S + 5.0)  # (past the stop's: not a deadline)
        f.feed()
        assert not f.says_turn()  # at rest a while after a stop went out
        f.restarted()
        to = round(PARTNER + 140.0)
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


def test_a_stream_of_targets_to_a_dcu1_writes_the_state_file_at_its_start_and_end_alone(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A logger or a tracking client turning a DCU-1 a few degrees every 10 s (each target a
    stop and a turn: rule 6 assumes the one before under way): the file says a turn is kept
    from the first target until TURN_KEPT_S after the last one's end, written twice, not
    twice per target (each target's stop had it written at rest, and again turning)."""
    with filed_dcu1(tmp_path, monkeypatch) as f:
        v = f.v
        f.feed()
        assert not f.says_turn()  # (no turn of the bridge's sent yet)
        before = f.writes
        bearing = round(PARTNER + 40.0)
        targets = 30
        for n in range(targets):
            v.target(bearing + 3 * n)
            v.run_for(10.0)  # (the next target's time: not a deadline)
            f.feed()
            assert f.says_turn(), n
        motion = v.cfg.motion  # (past its end, assumed for the whole range: not a deadline)
        v.run_for(mo.blind_busy_s(motion.az_span_deg, motion) + mo.TURN_KEPT_S + 5.0)
        f.feed()
        assert not f.says_turn()
        assert angle_between(v.truth().az_deg, bearing + 3 * (targets - 1)) <= 3.0
        assert f.writes - before == 2, f"{f.writes - before} state file writes"
        assert "turn_kept" not in json.loads(f.path.read_text())["rotators"][v.cfg.rotator_id]
