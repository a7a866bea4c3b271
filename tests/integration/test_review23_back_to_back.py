"""A guard: 0785d896 did what is said below, and was reverted (6129c849).

Cold review 23: ordinary use, an idle bridge, nothing lost. A Home Assistant script or a
Node-RED flow publishes two words back to back from one client: STOP then a new target ("stop,
then go there instead"), or lock ON then lock OFF. Each is published after the other, the
broker has them in that order, and nothing is behind on either connection. Since 0785d896 the
stop lane's hold ends by its marker alone, and the marker is published by the bridge only after
the lane read the STOP: the second word, already at the broker, reaches the main connection
before the marker and is refused as "published before a STOP or lock ON ... (or not known to be
after it)". The user's last word is not carried out, and R/error blames an order the user never
published.
"""

from __future__ import annotations

import time

from tests.integration.test_last_word import tower
from tests.support.rig import Rig


def test_stop_then_a_target_back_to_back_turns_to_the_target(rig: Rig) -> None:
    emu, app = tower(rig)
    rig.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving, 10)
    t = time.monotonic()
    rig.probe.publish("rotor/stop", "", qos=0)  # the script (QoS 0, HA's default): stop
    rig.probe.publish("rotor/target", "100", qos=0)  # ... then go to 100 instead
    time.sleep(1.0)
    errors = [m.payload for m in rig.probe.on("rotor/error") if m.t >= t]
    assert not [e for e in errors if b"target '100'" in e], (
        f"the target published after the STOP was refused as older: {errors}"
    )
    emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 100) <= 3, 30)


def test_lock_on_then_off_back_to_back_ends_unlocked(rig: Rig) -> None:
    """Three rounds (the two connections race for the ON when both are idle: the round the
    main connection reads it first, lastword.py rule 4, the lane's copy is its echo and holds
    nothing)."""
    _emu, app = tower(rig)
    left_locked = []
    for _round in range(3):
        t = time.monotonic()
        rig.probe.publish("rotor/lock", "ON", qos=0)  # a test of the lock, or a script's toggle
        rig.probe.publish("rotor/lock", "OFF", qos=0)  # the last word
        time.sleep(1.0)
        if app.rotators[0].status.locked:
            left_locked.append([m.payload for m in rig.probe.on("rotor/error") if m.t >= t])
            rig.probe.publish("rotor/lock", "OFF")  # (sent again, long after the marker)
            rig.probe.wait_value("rotor/lock/state", "OFF", 10)
    assert not left_locked, (
        f"lock ON then OFF, published in that order, left the rotator locked: {left_locked}"
    )
