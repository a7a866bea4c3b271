"""A guard: 0785d896 did what is said below, and was reverted (6129c849).

Cold review 23: since 0785d896 a lane hold ends by its marker alone (lastword.py rule 2); the
main connection's copy of the STOP, read in its order, no longer ends it. A marker the broker
dropped (QoS 0, a reader behind a flood: rule 5's own example) is sent again after RESEND_S,
the wait doubling up to RESEND_MAX_S (30 s). So once the flood is over and the main connection
has read everything, idle, the hold lasts until the next resend, up to 30 s later: every MQTT
target in that time is refused as "published before a STOP ... send it again", and sent again
it is refused again. Before, the copy of the STOP (read right after the flood) ended it.
"""

from __future__ import annotations

from bridge.interfaces.mqtt.halts import HELD
from bridge.interfaces.mqtt.lastword import RESEND_S
from tests.mqtt.test_service import RecordingRotator, saying_service


def test_a_hold_ends_soon_after_the_main_connection_has_caught_up_with_a_flood() -> None:
    clock, _said, pub, svc = saying_service()
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    pub.take()
    svc.on_lane_message("rotor/stop", b"", False)  # the operator's STOP, behind a flood
    for _ in range(63):  # a minute of a flood: the broker drops what the bridge sends itself
        clock.t += 1.0
        svc._halts.resend_if_due()
    pub.take()  # (every marker so far dropped for the reader behind)
    svc.on_message("rotor/stop", b"", False)  # the flood read, the main connection's copy
    ended_at = None
    for _ in range(40):  # the main connection idle: whatever the bridge sends comes back
        for topic, payload, _r in pub.take():
            if topic == "rotor/bridge/fence":
                svc.on_message(topic, payload.encode(), False)
        if any(c[0] == "release" for c in tower.calls):
            ended_at = clock.t
            break
        svc.on_message("rotor/target", b"120", False)  # the operator, once a second
        clock.t += 1.0
        svc._halts.resend_if_due()
    refused = [c for c in tower.calls if c[:2] == ("refused", HELD)]
    assert ended_at is not None and ended_at - 63 <= 2 * RESEND_S, (
        f"the hold ended {None if ended_at is None else ended_at - 63} s after the main "
        f"connection had read everything (idle), {len(refused)} targets published after the "
        "STOP refused meanwhile"
    )
