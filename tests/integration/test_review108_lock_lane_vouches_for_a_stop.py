"""Review 108: ``halts.read_since`` lets a lock ON the lock lane read stand for a stop the stop
express reads, because the lane "has had its command topics without a break since"; but the
lock lane subscribes to ``R/lock`` alone (lastword.py rule 16), so no STOP ever reaches it. With
the main connection and the stop lane away, a STOP only the express read (early: it writes no
frame, express.py rules 8, 11) is judged carried out by a lock ON of hours ago, and the bridge
drops it: the rotor turns on to its target.

Real mosquitto (an ACL dropping the express's sync words: it never writes, every stop it reads
is said early), the bridge in this process, the express in its own, a Rotor-EZ on a real pty; a
proxy in front of the broker cuts the main connection and the stop lane (and keeps them out)
while the lock lane and the express stay connected.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.integration.express_gate import OPEN, WORDS, Cutter, acl_conf
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until


@pytest.fixture
def broker_conf(tmp_path: Path) -> str:
    return acl_conf(tmp_path, f"{OPEN}topic deny {WORDS}\n")


def test_a_stop_only_the_express_read_is_not_vetoed_by_a_lock_on_of_the_lock_lane(
    tmp_path: Path, broker: Mosquitto
) -> None:
    cutter = Cutter(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, cutter, probe) as rig:
            rig.express = True
            emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            settings = rig.settings.mqtt
            app = rig.start()
            rig.ready("tower")
            wait_until(lambda: "tower" in app.express.held, 10, "the express holds the port")
            assert probe.publish("rotor/lock", "ON")  # work on the tower, then done
            probe.wait_value("rotor/lock/state", "ON")
            assert probe.publish("rotor/lock", "OFF")
            wait_until(lambda: not rig.status("tower").locked, 10, "unlocked")  # (both read)
            assert probe.publish("rotor/target", "300")  # a long turn (145 s)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            cutter.cut({settings.effective_client_id(), lane_client_id(settings)})
            wait_until(
                lambda: app.client.subscribed_since is None and app.lane.subscribed_since is None,
                15,
                "the main connection and the stop lane gone",
            )
            assert app.lock_lane.subscribed_since is not None  # (the lock lane stays)
            assert probe.publish("rotor/stop", "STOP")  # read by the express alone
            emu.wait_for(lambda s: not s.is_moving, slow(10))
    finally:
        probe.close()
        cutter.close()
