"""Cold review 22: the main connection's copy of a lane halt is "the oldest one the lane read of
that rotator and kind still waiting" (lastword.py rule 9). Both connections take commands at
QoS 0 (lane.py rule 2, client.py rules 1 and 4), so the count can be wrong (a halt lost on the
lane, one lost on the main connection), and a halt the main connection takes for a copy must
still be carried out: not carrying it out (as one change of this stop did) left a rotator
unlocked under the last word published, a lock ON.

lastword.py rule 13 (the fix): the count still decides what is refused (a move read before the
count copy of the hold's own halt), never what goes: a move read after it waits under the hold
for the marker, which the broker had after the lane's halt, so after its real copy; that copy,
read on the main connection when the count was off by a lost halt, drops what waits, as any
stop drops a target waiting before it. These tests say what the user sees: what reaches the
controller (the mailbox and the session's hold, modelled by ``controller``) and the lock.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import Stop, Target
from bridge.interfaces.mqtt.halts import LOCK_OFF_OLDER, LOCK_OFF_SUPERSEDED
from bridge.interfaces.mqtt.service import MqttService
from tests.mqtt.test_service import RecordingPublisher, service


def controller(calls: list[tuple[object, ...]]) -> tuple[list[float], bool | None]:
    """What reaches the controller from what the service handed the rotator, in order, as the
    mailbox and the session do it (mailbox.py rules 1 and 6, session/stops.py rule 5): a stop
    or lock ON drops the target waiting; a target waits while a hold is up, and goes when a
    release reaches it (a clearing one drops it; one after a stamped target's expiry, a release
    recorded with its time, drops it too). The targets' azimuths, and the lock last."""
    hold: int | None = None
    waiting: Target | None = None
    reached: list[float] = []
    locked: bool | None = None
    for call in calls:
        match call:
            case ("submit", Stop(), *rest):
                waiting = None
                if len(rest) > 1:
                    hold = max(hold or 0, int(str(rest[1])))
            case ("submit", Target() as target, *_):
                if hold is None:
                    reached.append(target.az_deg)
                else:
                    waiting = target
            case ("lock", on, *rest):
                locked = bool(on)
                if on:
                    waiting = None
                    if rest:
                        hold = max(hold or 0, int(str(rest[0])))
            case ("release", marker, *rest):
                at = next((r for r in rest if isinstance(r, float)), None)  # (when, if known)
                if "clear" in rest:
                    hold = waiting = None
                elif hold is not None and hold <= int(str(marker)):
                    hold = None
                    late = waiting is not None and waiting.not_after_s is not None
                    if late and at is not None and at > waiting.not_after_s:  # type: ignore[union-attr,operator]
                        waiting = None  # (session.py rule 13: past its stamp's expiry)
                    if waiting is not None:
                        reached.append(waiting.az_deg)
                        waiting = None
    return reached, locked


def markers_back(svc: MqttService, pub: RecordingPublisher) -> None:
    """The main connection reads what the bridge published on its marker topics."""
    for topic, payload, _retain in pub.take():
        if topic in ("rotor/bridge/fence", "rotor/bridge/hello"):
            svc.on_message(topic, payload.encode(), False)


def markers_back_late(
    svc: MqttService, pub: RecordingPublisher, wait: Callable[[float], None]
) -> None:
    """The marker, the fresh one sent at a copy and the first two resends lost in a flood
    (lastword.py rule 5's back-off, 2 s then 4 s: ``wait`` lets the time pass), the third,
    14 s on, read back by the main connection."""
    pub.take()
    for wait_s, back in ((2.0, False), (4.0, False), (8.0, True)):
        wait(wait_s)
        svc._halts.resend_if_due()  # noqa: SLF001  (the timer: a marker sent again)
        if back:
            markers_back(svc, pub)
        else:
            pub.take()  # lost again


def test_a_lock_on_lost_on_the_lane_is_carried_out_by_the_main_connection() -> None:
    """Published: lock ON 1, then (the console unlocks the rotator, its OFF waiting on the
    hold) lock ON 2, both within the marker's round trip. The lane reads ON 1 and loses ON 2;
    the main connection loses ON 1 (QoS 0 on both, a reader that fell behind) and reads ON 2:
    taken for ON 1's copy, it must still be carried out as a full lock ON."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    svc.on_lane_message("rotor/lock", b"ON", False)  # ON 1, carried out at once, on hold
    tower.calls.clear()
    svc.on_message("rotor/lock", b"ON", False)  # ON 2 (ON 1 lost on this connection)
    assert ("lock", True) in tower.calls, (
        f"a lock ON the lane never read was carried out by neither connection: {tower.calls}"
    )


def test_a_target_published_before_a_stop_is_not_sent_after_the_lane_carried_that_stop() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    # published: STOP 1, target 300, STOP 2. The lane lost STOP 1 (QoS 0) and read STOP 2.
    svc.on_lane_message("rotor/stop", b"", False)  # STOP 2, carried out at once, on hold
    svc.on_message("rotor/stop", b"", False)  # STOP 1, on the main connection (the count copy)
    svc.on_message("rotor/target", b"300", False)  # published before STOP 2: waits
    svc.on_message("rotor/stop", b"", False)  # STOP 2, its real copy: drops what waits
    markers_back(svc, pub)  # the markers come back: the hold ends
    svc.on_message("rotor/target", b"120", False)  # published after STOP 2: goes
    markers_back(svc, pub)
    reached, _locked = controller(tower.calls)
    assert reached == [120.0], (
        "a target published before the lane's STOP went to the controller after it (the "
        f"main connection's older STOP was taken for the lane STOP's copy): {tower.calls}"
    )


def test_a_lock_off_published_before_a_lane_lock_on_does_not_unlock_after_it() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    # published: lock ON 1, lock OFF, lock ON 2. The lane lost ON 1 and read ON 2 (carried out:
    # the rotator is locked, a climber may go up). ON 2 is the last word.
    svc.on_lane_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"ON", False)  # ON 1, on the main connection (the count copy)
    svc.on_message("rotor/lock", b"OFF", False)  # published before ON 2: waits
    assert controller(tower.calls)[1] is True  # (never unlocked meanwhile)
    svc.on_message("rotor/lock", b"ON", False)  # ON 2, its real copy
    markers_back(svc, pub)
    unlocked = [c for c in tower.calls if c[:2] == ("lock", False)]
    assert not unlocked and controller(tower.calls)[1] is True, (
        "a lock OFF published before the lane's lock ON unlocked the rotator after it: "
        f"{tower.calls}"
    )
    said = [c for c in tower.calls if c[0] == "refused" and c[2] == "lock OFF"]
    assert [c[1] for c in said] in ([LOCK_OFF_OLDER], [LOCK_OFF_SUPERSEDED]), tower.calls


def test_a_group_stop_the_lane_never_reads_is_not_the_copy_of_a_members_lane_stop() -> None:
    """The same without any loss: mosquitto checks a read ACL when it delivers, not at the
    SUBSCRIBE (the SUBACK grants it), so a lane user without read access to the group's stop
    topic never has a group stop, silently, every time. Published: the group's STOP, a target
    for a member, the member's own STOP. The lane reads only the member's STOP; the main
    connection's group STOP is taken for its copy, and the target published before the
    member's STOP waits, until the member's STOP drops it."""
    from tests.mqtt.test_groups import group_service

    svc, pub, upper, _lower = group_service()
    svc.on_lane_message("rotor/upper/stop", b"", False)  # the member's STOP (the lane's only)
    svc.on_message("rotor/stack/stop", b"", False)  # the group's STOP, published first
    svc.on_message("rotor/upper/target", b"200", False)  # published before the member's STOP
    svc.on_message("rotor/upper/stop", b"", False)  # the member's STOP, its real copy
    markers_back(svc, pub)
    reached, _locked = controller(upper.calls)
    assert not reached, (
        "a target published before the member's lane STOP went to the controller after it "
        f"(the group STOP was taken for that STOP's copy): {upper.calls}"
    )


def test_stop_then_a_target_back_to_back_ends_at_the_target() -> None:
    """The guard (review 23): the count copy right, the target published after the STOP waits
    for the marker, then goes; a lock ON then OFF ends unlocked, never unlocked in between."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    svc.on_lane_message("rotor/stop", b"", False)
    svc.on_message("rotor/stop", b"", False)  # its copy
    svc.on_message("rotor/target", b"100", False)  # published after it
    assert controller(tower.calls)[0] == []  # (waits for the marker)
    markers_back(svc, pub)
    assert controller(tower.calls)[0] == [100.0]
    svc.on_lane_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"OFF", False)
    assert controller(tower.calls)[1] is True
    markers_back(svc, pub)
    assert controller(tower.calls)[1] is False
