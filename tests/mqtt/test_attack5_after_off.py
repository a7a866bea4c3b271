"""Attack pass 5 on lastword.py rule 13: the moves the main connection reads after a lock OFF
that waits under a lane hold for its marker.

The version attacked kept every such move (one closure each, no bound) and ran them all at the
marker under the halts lock, the lock a stop lane's halt needs: a flood read while the OFF
waited grew memory with every message and delayed the next lane STOP; and a move read after a
newer lock ON was dropped at the marker without a word. Now one move is kept, the newest (as
the mailbox keeps the newest target), put after the OFF at the marker; one the OFF's refusal
leaves behind is said on R/error.

``LockJudged`` refuses a move while the lock is ON, as runtime/rotator.py's judge does.
"""

from __future__ import annotations

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import Command, Lock, Target
from tests.mqtt.test_review22_lost_lane_copy import markers_back
from tests.mqtt.test_service import RecordingRotator, service


class LockJudged(RecordingRotator):
    locked = False

    def submit(self, command: Command, described: str | None = None, **kw: object) -> None:  # type: ignore[override]
        if isinstance(command, Target) and self.locked:
            self.calls.append(("refused", "locked", described))
            raise Refused(RefusalCode.LOCKED, "locked")
        super().submit(command, described, **kw)  # type: ignore[arg-type]
        if isinstance(command, Lock):
            self.locked = command.on


def _lock_off_waiting():  # type: ignore[no-untyped-def]
    svc, pub, _rots = service({"tower": "rotorez"})
    tower = LockJudged("tower", "rotorez")
    svc.attach(tower)
    pub.take()
    svc.on_lane_message("rotor/lock", b"ON", False)  # lane ON, carried at once: hold
    svc.on_message("rotor/lock", b"ON", False)  # its copy (counted)
    svc.on_message("rotor/lock", b"OFF", False)  # waits for the marker (rule 13)
    assert tower.locked  # (never unlocked before the marker)
    return svc, pub, tower


def test_a_flood_read_after_a_waiting_lock_off_keeps_the_newest_target_only() -> None:
    svc, pub, tower = _lock_off_waiting()
    flood = 5_000
    for i in range(flood):
        svc.on_message("rotor/target", str(i % 360).encode(), False)
    assert not [c for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    assert len(svc._halts._after_off) == 1  # noqa: SLF001 (what is kept: one move, the newest)
    tower.calls.clear()
    markers_back(svc, pub)
    moved = [c[1].az_deg for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    assert not tower.locked, "the lock OFF that waited did not go at the marker"
    assert moved == [float((flood - 1) % 360)], (
        f"the marker's release put {len(moved)} targets (the newest alone is the last word)"
    )


def test_a_target_read_after_a_newer_lock_on_is_said_on_r_error() -> None:
    svc, pub, tower = _lock_off_waiting()
    svc.on_message("rotor/lock", b"ON", False)  # a newer lock ON, main connection, carried
    svc.on_message("rotor/target", b"200", False)  # published after that lock ON
    markers_back(svc, pub)
    moved = [c for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    refused = [c for c in tower.calls if c[0] == "refused" and c[2] == "target '200'"]
    assert not moved and tower.locked  # (the lock is ON: it must not go)
    assert refused, f"a target read after a lock ON was dropped without a word: {tower.calls}"
