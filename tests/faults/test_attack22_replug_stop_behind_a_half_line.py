"""Attack 22, on a real pty with real mosquitto: the stop a GS-232B is owed across an unplug is
read, on replug, behind the half frame the adapter left in the box, and is refused.

A STOP comes while the adapter is out (the rotor turning on by itself): the bridge owes it and
sends it first when the port is back (session/controller.py ``connect``: "before anything else
the controller gets" it). The box still holds the first byte of the frame the unplug cut (an
``S``: the stop written as the adapter went; a poll's ``C`` does the same), and nothing the
bridge sends ends that half line first: the box reads ``SS`` CR, answers ``?>``, which the
bridge passes over as bytes that are no reply, and turns on until the stop is checked and sent
again, ``stop_resend_s`` (2 s) later. The virtual-time twin is
tests/engine/test_attack22_torn_stop_eats_the_replug_stop.py.
"""

from __future__ import annotations

import json
import time

from bridge.emulators.gs232 import Outcome
from tests.faults.conftest import Rig
from tests.support.waiting import slow


def test_the_stop_owed_across_an_unplug_is_the_first_command_the_box_takes(rig: Rig) -> None:
    rig.add("gs", "gs232b", emu={"start_az_deg": 10, "az_speed_deg_s": 10.0})
    rig.start()
    rig.ready("gs")
    emu = rig.emus["gs"]
    rig.probe.publish(rig.topic("gs", "target"), "350")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 20, slow(10))
    t = time.monotonic()
    emu.unplug()
    rig.probe.wait_value(rig.topic("gs", "availability"), "offline", slow(5), after=t)
    emu.inject(b"S", to="device")  # the first byte of the frame the unplug cut
    rig.probe.publish(rig.topic("gs", "stop"), "STOP")  # while the port is out: owed
    t = time.monotonic()
    rig.probe.publish(rig.topic("gs", "target"), "100")  # refused offline, after the STOP
    rig.probe.wait_for(
        rig.topic("gs", "error"),
        lambda m: json.loads(m.payload).get("command") == "target '100'",
        after=t,
    )
    logged = len(emu.log())
    assert emu.state().is_moving
    emu.replug(power_cycle=False)
    emu.wait_until(lambda device, _now: len(device.log), lambda n: n > logged, slow(10))
    first = emu.log()[logged]
    assert first.outcome == Outcome.STOP, emu.log()[logged : logged + 4]
