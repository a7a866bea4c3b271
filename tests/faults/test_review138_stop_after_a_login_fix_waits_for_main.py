"""Review 138, with real mosquitto: e2da6bcf has a stop carrier (the stop lane, the lock lane,
the express) whose login the broker refused wait for the main connection before it tries again
(connection.py rule 6, review 81). The main connection's back-off doubles to 30 s while the
broker refuses it; once the broker's admin fixes the login, the stop carriers stay down until the
main connection's next try, up to 30 s later, and a STOP sent meanwhile reaches nobody: the rotor
turns on to its target (attack 23's window, back). Before e2da6bcf each tried every 2 s.
"""

from __future__ import annotations

import contextlib
import time
from pathlib import Path

from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

REFUSED_S = 16.0  # the refusal's length: the main connection's tries at 1, 3, 7, 15 s, next 31 s
AFTER_FIX_S = 4.0  # a STOP sent this long after the fix at most (twice a stop carrier's back-off)


def test_a_stop_sent_soon_after_the_login_is_fixed_stops_the_rotor(tmp_path: Path) -> None:
    broker = Mosquitto(tmp_path / "broker").start()
    probe = Probe(broker.port, "rotor/#")
    try:
        with Rig(tmp_path, broker, probe) as rig:
            rig.express = True
            emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 5.0})
            app = rig.start()
            rig.ready("tower")
            wait_until(app.lock_lane.connected.is_set, 10, "the lock lane up")
            wait_until(app.express.up.is_set, 10, "the express up")
            probe.publish("rotor/target", "350")  # a long turn: some 68 s
            emu.wait_for(lambda s: s.is_moving, slow(10))
            broker.extra_conf = "allow_anonymous false"  # an upgrade: the login refused
            broker.stop()
            broker.start()
            time.sleep(REFUSED_S)  # the fault's length, not a deadline
            broker.extra_conf = ""  # the admin's fix
            broker.stop()
            broker.start()
            wait_until(probe.client.is_connected, 10, "the dashboard back on the broker")
            # the user's STOP: once the stop lane is back, or AFTER_FIX_S after the fix at most
            with contextlib.suppress(TimeoutError):
                wait_until(app.lane.connected.is_set, AFTER_FIX_S, error=TimeoutError)
            probe.publish("rotor/stop", "STOP")
            try:
                state = emu.wait_for(lambda s: not s.is_moving, slow(10))
            except TimeoutError:
                state = emu.state()
            lane_up = app.lane.connected.is_set()
    finally:
        probe.close()
        broker.stop()
    assert not state.is_moving and state.az_deg < 300, (
        f"a STOP sent at most {AFTER_FIX_S:g} s after the login was fixed did not stop the rotor: "
        f"{state.az_deg:.0f} deg, moving {state.is_moving} (the stop lane up: {lane_up})"
    )
