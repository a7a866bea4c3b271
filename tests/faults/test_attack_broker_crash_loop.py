"""Attack: a broker that crashes and is restarted at once (systemd's Restart=always, RestartSec
100 ms by default) a few times in a row. Each time the bridge's first reconnect (after its 1 s
delay) finds the broker back, so the three short connections look to rule 7
(interfaces/mqtt/connection.py) exactly like a fight over the client id: the bridge backs off
5 s, 10 s, ... 60 s between reconnects, and for that long it hears no STOP at all."""

from __future__ import annotations

import time

import pytest

from tests.faults.conftest import Rig
from tests.support import wait_until


def crash_and_restart(rig: Rig) -> None:
    rig.broker.kill()  # no goodbye
    time.sleep(0.1)  # systemd's RestartSec default
    rig.broker.start()


@pytest.mark.parametrize("express", [False, True], ids=["lane", "express"])
def test_a_stop_after_a_broker_crash_loop_still_stops_the_rotor(rig: Rig, express: bool) -> None:
    rig.express = express
    emu = rig.add("tower", "rotorez", emu={"start_az_deg": 0, "jitter_deg": 0, "speed_deg_s": 6})
    rig.start()
    rig.ready("tower")
    for _ in range(4):  # four crashes, each a second after the bridge came back (3 can race)
        crash_and_restart(rig)
        t = time.monotonic()
        rig.probe.wait_value("rotor/bridge/state", "online", timeout_s=20, after=t)
        time.sleep(1.0)
    rig.probe.publish("rotor/target", "350")
    wait_until(lambda: emu.state().is_moving, 10, "the rotor turns")
    crash_and_restart(rig)  # once more, while it turns
    # the broker is back and stays up; the operator waits 5 s, sees the rotor turn, presses STOP
    time.sleep(5.0)
    assert emu.state().is_moving
    rig.probe.publish("rotor/stop", "STOP")
    wait_until(lambda: not emu.state().is_moving, 3, "the rotor stopped by the STOP")
