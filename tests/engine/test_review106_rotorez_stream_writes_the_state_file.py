"""Review 106 (Low: wear, no wrong motion): the target a Rotor-EZ rests short of
(runtime/kept.py rule 9, ``short_of``) is saved whenever it changes, "at a stop short of the
target, and at the next turn": two full rewrites of the state file, each with its fsyncs, at
each such stop. The session's own stop before a new bearing (the Rotor-EZ stops on a new
bearing while turning and ignores bearings in its brake delay: protocols/base.py
``RetargetPolicy``) rests the rotor short of the last target written, so a
stream of targets faster than the rotor writes the file every few targets, the wear
review 92 took out of the order's places (``ORDER_SAVES`` in ``ORDER_WINDOW_S``) and review 93
out of a DCU-1's turn kept: "a tracker must not write it per target".

What a user sees: Gpredict through rotctld (its default cycle: a second) follows a fast
pass with a Rotor-EZ, a bearing a degree on every second for five minutes; the state file on
the station's SD card is rewritten and fsynced some ninety times, where the same stream to a
GS-232B writes it eight times (the places, the version). In virtual time, every status handed
to the rotator's Kept as runtime/rotator.py ``_status`` does, on a real state file, its
writes counted."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.runtime.kept import ORDER_SAVES, Kept
from bridge.runtime.state_store import StateStore
from tests.engine.virtual import VirtualRotator

EVERY_S = 1.0  # a tracking client's bearing every second (Gpredict's default cycle) ...
STEP_DEG = 1.0  # ... a degree on from the last
START_DEG = 60.0  # from 60 ...
TARGETS = 299  # ... to 358: five minutes


def writes_for_a_stream(model: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> int:
    """The state file's writes while ``model`` is sent the stream."""
    v = VirtualRotator(model)
    try:
        v.run_until(lambda h: h.status.available, 30, "the controller answers")
        store = StateStore(tmp_path / f"{model}.json", boot=lambda: ("boot", 43200.0 + v.now))

        def report(*said: object) -> None:
            raise AssertionError(said)

        kept = Kept(store, v.cfg.rotator_id, v.cfg.spec, report=report, clock=lambda: v.now)
        writes = [0]
        real = StateStore._write

        def counted(s: StateStore, at: Path, *, put_in_place: bool = True) -> None:
            writes[0] += 1
            real(s, at, put_in_place=put_in_place)

        monkeypatch.setattr(StateStore, "_write", counted)
        fed = 0

        def feed() -> None:
            nonlocal fed
            for _t, status in v.statuses[fed:]:  # (as runtime/rotator.py ``_status``)
                kept.seen_wind(status.wind)
                kept.seen_stop(status.stop_owed)
                kept.seen_short_of(status.short_of_deg)
                kept.seen_turn(status.turn_kept, status.turn_kept_until)
                kept.seen_version(status.version)
                kept.seen_order(status.order)
            fed = len(v.statuses)
            store.flush()

        feed()
        before = writes[0]
        for n in range(TARGETS):
            v.target(START_DEG + STEP_DEG * n)  # (up to 359)
            v.run_for(EVERY_S)  # (the client's next bearing: not a deadline)
            feed()
        return writes[0] - before
    finally:
        v.close()


def test_the_stream_to_a_gs232b_writes_the_state_file_a_few_times(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The control: the places (rule 12's ORDER_SAVES) and the version, nothing per target."""
    assert writes_for_a_stream("gs232b", tmp_path, monkeypatch) <= ORDER_SAVES + 2


@pytest.mark.xfail(
    strict=True,
    reason="review 106 (its fix 88df070b reverted: review 109 found a restart under the "
    "express's hold left unguarded): a stream of targets to a Rotor-EZ rewrites and fsyncs the "
    "state file "
    "every few targets (short_of saved at a retarget's stop and turn): 90 writes in 5 min",
)
def test_the_stream_to_a_rotorez_writes_the_state_file_a_few_times(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    writes = writes_for_a_stream("rotorez", tmp_path, monkeypatch)
    assert writes <= ORDER_SAVES + 2, f"{writes} state file writes for {TARGETS} targets"
