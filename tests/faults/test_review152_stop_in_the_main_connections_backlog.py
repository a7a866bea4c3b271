"""Review 152 (cold review of 415730e0): review 148's known failure was that a STOP pressed
while the stop lane was away for a few seconds' stall of its uplink waited behind the backlog
the main connection was reading (late, but carried out once the backlog was read). Since
415730e0 the stop lane, answered again, puts the main connection's path in doubt
(connection.py rule 6, ``prove_path``): the main connection's PINGRESP waits behind the same
backlog, the bridge gives the healthy main connection up within 2 s, and the STOP, which only
the main connection had (the lane was not subscribed when it was published), goes with it:
the rotor turns on to its target.

Real parts: mosquitto, the bridge in-process, an emulated Rotor-EZ on a pty, a paho client at
the broker's own port as the dashboard, the MQTT-aware proxy on the bridge's path: the stop
lane's uplink held (a new connection passes), what the broker sends the main connection held
(review 145's ``SlowPath``) and then let go.

Now a guard: 415730e0 was taken back (the main connection keeps its keep-alive); any later
way of finding the main connection's dead path must pass it."""

from __future__ import annotations

import contextlib
from pathlib import Path

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.faults.behind_a_proxy import TOWER, lanes_behind
from tests.faults.test_review145_stop_carriers_keepalive import SlowPath
from tests.support.tap import near_deg
from tests.support.waiting import slow, wait_until

# 415730e0's DEAD_PATH_S (taken back): how long after a dead path or a lane's return a
# doubted main connection was made again at most
DEAD_PATH_S = 12

TARGET = "300"  # from 10 deg at 2 deg/s: 145 s under way, past every deadline below
SHORT_DEG = 20.0  # a stopped rotor is this far from its target at least
PROMPT_S = 10.0  # the backlog read, the STOP reaches the controller within this


def test_a_stop_behind_the_main_connections_backlog_is_carried_out_once_it_is_read(
    tmp_path: Path,
) -> None:
    # a dashboard on the broker's own port; the tower at 10 deg, 2 deg/s; no wait for the lock lane
    with lanes_behind(tmp_path, lambda port: SlowPath(port, 0.0), emu=TOWER, lock_lane=False) as b:
        proxy, probe, rig, emu, app = b.proxy, b.probe, b.rig, b.emu, b.app
        probe.publish("rotor/target", TARGET)  # a long turn
        emu.wait_for(lambda s: s.is_moving, slow(10))
        proxy.backlog(rig.settings.mqtt.effective_client_id())  # the main one's reading
        proxy.hold(lane_client_id(rig.settings.mqtt))  # the lane's uplink stalls
        wait_until(lambda: not app.lane.connected.is_set(), slow(10), "the lane gone")
        assert probe.publish("rotor/stop", "")  # the operator's STOP, at the broker
        wait_until(app.lane.connected.is_set, slow(15), "the lane back")
        # the main connection's doubt settled (or not) within DEAD_PATH_S of the lane's return
        with contextlib.suppress(AssertionError, TimeoutError):
            wait_until(
                lambda: not app.client.connected.is_set(),
                slow(DEAD_PATH_S),
                "the main connection given up",
            )
        main_up = app.client.connected.is_set()
        proxy.released.set()  # the backlog read
        with contextlib.suppress(AssertionError, TimeoutError):
            emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
        s = emu.state()
        assert not s.is_moving and not near_deg(s.az_deg, float(TARGET), SHORT_DEG), (
            f"a STOP pressed while the stop lane was away and the main connection read a "
            f"backlog was never carried out: the rotor turns on ({s.az_deg:.0f} deg); the "
            f"main connection kept: {main_up}"
        )
