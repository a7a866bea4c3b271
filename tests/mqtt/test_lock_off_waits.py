"""lastword.py rule 13: a lock OFF the main connection reads under a hold with a lane lock ON
among its halts waits for the marker, with the newest move read after it; what ends it."""

from __future__ import annotations

from bridge.core.model import Lock, Source, Stop, Target
from bridge.interfaces.mqtt.halts import (
    AFTER_OFF_REFUSED,
    FENCED,
    LOCK_OFF_FENCED,
    LOCK_OFF_LOST,
    MOVE_LOST,
)
from tests.mqtt.test_review22_lost_lane_copy import controller, markers_back
from tests.mqtt.test_service import service


def _waiting():  # type: ignore[no-untyped-def]
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    svc.on_lane_message("rotor/lock", b"ON", False)  # the lane first: carried out, on hold
    svc.on_message("rotor/lock", b"ON", False)  # its copy (counted)
    svc.on_message("rotor/lock", b"OFF", False)  # waits for the marker
    svc.on_message("rotor/target", b"250", False)  # kept behind it
    assert controller(tower.calls) == ([], True)  # (nothing unlocked, nothing moved yet)
    return svc, pub, tower


def _refused(calls: list[tuple[object, ...]]) -> list[tuple[object, object]]:
    return [(c[1], c[2]) for c in calls if c[0] == "refused"]


def test_lock_on_off_then_a_target_end_unlocked_at_the_target_at_the_marker() -> None:
    svc, pub, tower = _waiting()
    markers_back(svc, pub)
    assert controller(tower.calls) == ([250.0], False), tower.calls
    assert _refused(tower.calls) == []


def test_a_lock_off_under_a_stops_hold_alone_goes_at_once() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    svc.on_message("rotor/lock", b"ON", False)  # locked earlier, in order
    svc.on_lane_message("rotor/stop", b"", False)  # a STOP, the lane first: on hold
    svc.on_message("rotor/stop", b"", False)  # its copy
    svc.on_message("rotor/lock", b"OFF", False)  # no lane lock ON to be older than: goes
    assert controller(tower.calls)[1] is False, tower.calls


def test_another_interfaces_lock_on_while_the_off_waits_keeps_the_lock_on() -> None:
    svc, pub, tower = _waiting()
    svc.fence_asked("tower")
    tower.submit(Lock(True, source=Source.WEB))  # the console's lock ON, after both
    svc.fence_carried("tower", lock=True)
    markers_back(svc, pub)
    moved = [c for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    assert not moved and controller(tower.calls)[1] is True, tower.calls
    assert _refused(tower.calls) == [
        (LOCK_OFF_FENCED, "lock OFF"),
        (AFTER_OFF_REFUSED, "target '250'"),
    ]


def test_another_interfaces_stop_while_the_off_waits_drops_the_move_not_the_off() -> None:
    svc, pub, tower = _waiting()
    svc.fence_asked("tower")
    tower.submit(Stop(Source.ROTCTLD))  # rotctld's S, after both
    svc.fence_carried("tower", lock=False)
    markers_back(svc, pub)
    assert controller(tower.calls) == ([], False), tower.calls


def test_a_stop_read_after_the_move_drops_it_and_leaves_the_off() -> None:
    svc, pub, tower = _waiting()
    svc.on_message("rotor/stop", b"", False)  # published after the target: the later word
    markers_back(svc, pub)
    assert controller(tower.calls) == ([], False), tower.calls
    assert _refused(tower.calls) == []


def test_another_interfaces_halt_under_way_at_the_marker_keeps_the_lock_on() -> None:
    svc, pub, tower = _waiting()
    svc.fence_asked("tower")  # asked, not yet put: it may be a lock ON
    markers_back(svc, pub)
    assert controller(tower.calls) == ([], True), tower.calls
    assert _refused(tower.calls)[0] == (LOCK_OFF_FENCED, "lock OFF")


def test_the_main_connection_dropping_says_both_lost() -> None:
    svc, pub, tower = _waiting()
    svc.main_gone()
    assert controller(tower.calls) == ([], True), tower.calls
    assert _refused(tower.calls) == [(LOCK_OFF_LOST, "lock OFF"), (MOVE_LOST, "target '250'")]


def test_a_move_under_another_interfaces_fence_is_refused_not_kept() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    svc.on_lane_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"OFF", False)
    svc.fence_asked("tower")  # rotctld's S under way
    svc.on_message("rotor/target", b"250", False)  # read meanwhile: published before it
    assert (FENCED, "target '250'") in _refused(tower.calls)
    svc.fence_carried("tower", lock=False)
    markers_back(svc, pub)
    assert controller(tower.calls) == ([], False), tower.calls
