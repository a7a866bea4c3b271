"""Attack pass 5 on lastword.py rule 13 (halts.py ``_release``): a lock OFF that waits under a
lane hold is submitted at the marker with the halt count read when it was *read*
(``since``). The judge (runtime/rotator.py ``_lock``) refuses a lock OFF while the lock is ON
if *any* stop or lock ON was put since that count (``mailbox.epoch != since``). halts.py
drops the waiting OFF for a newer lock ON only (``_lock_ons``), on purpose; but a STOP the
main connection reads after the OFF (published after it: Home Assistant's, a Node-RED flow's
routine STOP, the operator's own STOP right after unlocking), or any interface's STOP while
it waits, moves the epoch, and the OFF is refused at the marker: the lock stays ON although
its last word was OFF. Read without a hold (no lane halt), the same OFF then STOP unlocks.

``JudgedRotator`` keeps the judge's halt count and its rule for a lock OFF, as
runtime/rotator.py does (``halts`` is ``mailbox.epoch``; a stop or lock ON moves it).
"""

from __future__ import annotations

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import Command, Lock, Stop
from tests.mqtt.test_review22_lost_lane_copy import markers_back
from tests.mqtt.test_service import RecordingRotator, service


class JudgedRotator(RecordingRotator):
    def __init__(self, *args: object, **kw: object) -> None:
        super().__init__(*args, **kw)  # type: ignore[arg-type]
        self.epoch = 0
        self.locked = False

    @property
    def halts(self) -> int:
        return self.epoch

    def submit(self, command: Command, described: str | None = None, **kw: object) -> None:  # type: ignore[override]
        since = kw.get("since")
        if isinstance(command, Lock) and not command.on and since is not None and self.locked:
            if self.epoch != since:  # runtime/rotator.py _lock
                self.calls.append(("refused", "stale lock OFF", "lock OFF"))
                raise Refused(RefusalCode.STALE, "stale lock OFF")
        super().submit(command, described, **kw)  # type: ignore[arg-type]
        if isinstance(command, Lock):
            self.locked = command.on
            if command.on:
                self.epoch += 1
        elif isinstance(command, Stop):
            self.epoch += 1


def _service():  # type: ignore[no-untyped-def]
    svc, pub, rots = service({"tower": "rotorez"})
    judged = JudgedRotator("tower", "rotorez")
    svc.attach(judged)
    pub.take()
    return svc, pub, judged


def test_without_a_hold_lock_off_then_stop_ends_unlocked() -> None:
    svc, pub, tower = _service()
    svc.on_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"OFF", False)
    svc.on_message("rotor/stop", b"", False)
    assert tower.locked is False


def test_a_lock_off_that_waited_under_a_hold_is_not_undone_by_a_later_stop() -> None:
    svc, pub, tower = _service()
    svc.on_lane_message("rotor/lock", b"ON", False)  # lock ON, lane first: hold
    svc.on_message("rotor/lock", b"ON", False)  # its copy (counted)
    svc.on_message("rotor/lock", b"OFF", False)  # the operator unlocks: waits (rule 13)
    svc.on_message("rotor/stop", b"", False)  # then a STOP, published after the OFF
    markers_back(svc, pub)
    assert tower.locked is False, (
        "a lock OFF that waited for the marker was refused as stale at the marker because a "
        f"STOP published after it moved the halt count: the lock stays ON: {tower.calls}"
    )
