"""Stop and lock on a connection of their own (interfaces/mqtt/lane.py; issue 14, item 13): a stop
published behind a flood of targets waited until the bridge had read every one of them
(stops 0.85 to 3.9 s late). Real parts: mosquitto, the bridge (App) and an emulated Rotor-EZ.

The flood is stood in for by a main connection that cannot read at all: its handler is held
on a target until the test lets it go. A stop and a lock published after that target must
reach the rotator while the target still holds the main connection."""

from __future__ import annotations

import threading
import time

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until


def test_a_stop_and_the_lock_get_through_while_the_targets_connection_is_stuck(rig: Rig) -> None:
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
    app = rig.start()
    rig.ready("tower")
    release = threading.Event()
    held = threading.Event()
    handle = app.mqtt.on_message

    def stuck(topic: str, payload: bytes, retain: bool, operator: str | None, *_: object) -> None:
        if topic == "rotor/target" and payload == b"300":
            held.set()
            release.wait(slow(30))  # the main connection reads nothing more meanwhile
        handle(topic, payload, retain, operator)

    app.client._handler = stuck  # the main connection's hand-off (client.py rule 5)
    try:
        rig.probe.publish("rotor/target", "200")
        emu.wait_for(lambda s: s.is_moving, 10)
        rig.probe.publish("rotor/target", "300")
        wait_until(held.is_set, 10, "the main connection is stuck on a target")
        stops = len(emu.frames("stop"))
        t = time.monotonic()
        rig.probe.publish("rotor/stop", "")
        emu.wait_until(lambda d, now: len(d.frames("stop")), lambda n: n > stops, 10)
        emu.wait_for(lambda s: not s.is_moving, 10)
        rig.probe.publish("rotor/lock", "ON")
        # (its lock/state goes out on the main connection, whose thread the test holds)
        wait_until(lambda: app.rotators[0].status.locked, 10, "locked")
        assert held.is_set() and not release.is_set()  # all of it with the main one stuck
    finally:
        release.set()
    rig.probe.wait_value("rotor/lock/state", "ON", 10, after=t)
    # the target the main connection was stuck on was published before the stop and the lock:
    # read at last, before the main connection's copy of either, it is refused as older than
    # the lane's halts (lastword.py rule 2), never carried out after the stop (cold review:
    # the rotor halted, then went on to it by itself)
    err = rig.probe.wait_for("rotor/error", lambda m: b"300" in m.payload, 10, after=t)
    assert b"that the stop connection carried out first" in err.payload
    wait_until(lambda: not app.mqtt._word.holding, 10, "the main connection caught up")
    wait_until(lambda: not app.client.gated and app.rotators[0].status.locked, 5, "settled")
    rig.probe.publish("rotor/lock", "OFF")  # in order with the targets: the next one is obeyed
    rig.probe.publish("rotor/target", "250")
    emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 250) <= 3, 30)
    sent = [f.data for f in emu.frames(*BEARING_OUTCOMES)]
    assert not [d for d in sent if b"300" in d], sent  # the dropped target never went out
