"""Attack: a broker that crashes and is restarted at once (systemd's Restart=always, RestartSec
100 ms by default) a few times in a row. Each time the bridge's first reconnect (after its 1 s
delay) found the broker back, so the three short connections looked to rule 7
(interfaces/mqtt/connection.py) exactly like a fight over the client id: the bridge backed off
5 s, 10 s, ... 60 s between reconnects, and for that long it heard no STOP at all. The stop
lane and the stop express back off 5 s at most; the broker's port, closed right after each drop,
now says it went away (whether the bridge looks before systemd's 100 ms are up depends on the
machine's load: tests/mqtt/test_client_takeover.py proves that look with a port kept closed
longer)."""

from __future__ import annotations

import time

import pytest

from bridge.interfaces.mqtt.connection import TAKEOVER_FIRST_S
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
    # the broker is back and stays up; the operator waits a little, sees the rotor turn, presses
    # STOP: a connection that carries stops backs off TAKEOVER_FIRST_S at most, even when the
    # bridge, busy, looked at the broker's port too late to see it closed (connection.py rule 7)
    time.sleep(TAKEOVER_FIRST_S + 2.0)
    assert emu.state().is_moving
    rig.probe.publish("rotor/stop", "STOP")
    wait_until(lambda: not emu.state().is_moving, 3, "the rotor stopped by the STOP")
