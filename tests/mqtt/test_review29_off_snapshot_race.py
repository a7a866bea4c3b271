"""Cold review 29: a lock OFF that waits under a lane hold (lastword.py rule 13) is judged at
the marker against the lock ONs counted when it was put to wait (halts.py ``_lock_ons``), and
no longer against the halt count read when it was read (``since``). ``main_lock_off`` reads
``fenced`` outside the halts lock, then takes the lock and takes that snapshot: another
interface's lock ON (the console, rotctld) asked, put and fenced between the two is inside the
snapshot and outside ``fenced``. Once the fence ends before the hold does (the fence's
marker back with the hold's fresh marker lost, or a lane STOP read meanwhile renewing the hold
past the fence's marker, no message lost; or the markers found denied, rule 15, which clears
the fences), the OFF, published before that lock ON, unlocks the rotator at the hold's end.
Before rule 13 the same OFF went to the judge with the count read first, and was refused.
"""

from __future__ import annotations

from bridge.core.model import Lock, Source
from tests.mqtt.test_attack5_off_after_stop import JudgedRotator
from tests.mqtt.test_review22_lost_lane_copy import markers_back
from tests.mqtt.test_service import service


def test_a_console_lock_on_between_the_offs_look_and_its_wait_keeps_the_lock_on() -> None:
    svc, pub, _rots = service({"tower": "rotorez"})
    tower = JudgedRotator("tower", "rotorez")
    svc.attach(tower)
    pub.take()
    svc.on_lane_message("rotor/lock", b"ON", False)  # the lane first: carried out, on hold
    svc.on_message("rotor/lock", b"ON", False)  # its copy (counted): a fresh marker goes
    pub.take()  # that marker lost on both topics (a reader that fell behind)
    halts = svc._halts  # noqa: SLF001 (the window between two statements of main_lock_off)
    real = halts.fenced
    once: list[bool] = []

    def fenced(rotator_id: str, lock_off: bool = False) -> bool:
        answer = real(rotator_id, lock_off)
        if lock_off and not once:  # the console's lock ON lands right after the look
            once.append(True)
            svc.fence_asked("tower")
            tower.submit(Lock(True, source=Source.WEB))
            svc.fence_carried("tower", lock=True)
        return answer

    halts.fenced = fenced  # type: ignore[method-assign]
    svc.on_message("rotor/lock", b"OFF", False)  # read before the console's lock ON
    halts.fenced = real  # type: ignore[method-assign]
    assert tower.locked
    markers_back(svc, pub)  # the console's fence marker, the only one out
    assert tower.locked, f"an OFF read before the console's lock ON unlocked: {tower.calls}"


def test_the_same_with_no_message_lost_a_lane_stop_outlasting_the_fence() -> None:
    """No message lost: a STOP the lane reads before the fresh marker is back renews the hold
    past the console's fence marker, which ends the fence first; the hold's own marker then
    lets the OFF go, the console's lock ON in its snapshot."""
    svc, pub, _rots = service({"tower": "rotorez"})
    tower = JudgedRotator("tower", "rotorez")
    svc.attach(tower)
    pub.take()
    svc.on_lane_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"ON", False)  # its copy (counted): a fresh marker goes
    halts = svc._halts  # noqa: SLF001
    real = halts.fenced
    once: list[bool] = []

    def fenced(rotator_id: str, lock_off: bool = False) -> bool:
        answer = real(rotator_id, lock_off)
        if lock_off and not once:
            once.append(True)
            svc.fence_asked("tower")
            tower.submit(Lock(True, source=Source.WEB))
            svc.fence_carried("tower", lock=True)
        return answer

    halts.fenced = fenced  # type: ignore[method-assign]
    svc.on_message("rotor/lock", b"OFF", False)  # read before the console's lock ON
    halts.fenced = real  # type: ignore[method-assign]
    earlier = pub.take()  # the fresh marker and the fence's, published before the STOP
    svc.on_lane_message("rotor/stop", b"", False)  # a STOP published later, the lane first
    for topic, payload, _retain in earlier:  # the main connection reads them, then the STOP
        svc.on_message(topic, payload.encode(), False)
    assert tower.locked  # (the fence's marker ended the fence; the STOP's hold holds)
    svc.on_message("rotor/stop", b"", False)  # the STOP's copy
    markers_back(svc, pub)  # the STOP's marker and the fresh one after its copy
    assert tower.locked, f"an OFF read before the console's lock ON unlocked: {tower.calls}"
