"""Review 152 (cold review of 415730e0): a lane accepted again after it gave a connection up for
an unanswered ping now puts the main connection's path in doubt (connection.py rule 6,
``prove_path``): the main connection pings within STOP_KEEPALIVE_S and, unanswered, is made
again. But a lane's ping goes unanswered for more than a dead path: review 148's few seconds'
stall of the uplink (the bytes held, not lost) ends the stop lane too, and its new connection
is accepted at once. If the main connection is reading a backlog at that moment (what the
broker sends it held behind a flood: review 145's ``SlowPath``), its PINGRESP waits behind the
backlog, and the main connection, whose path was fine all along, is given up by the bridge
itself: the broker publishes its will, every dashboard is shown the rotator ``offline``, and
the backlog it was reading is thrown away. Before 415730e0 (the setting's keep-alive, 30 s) the
same spell ended nothing on the main connection.

Real parts: mosquitto, the bridge in-process, an emulated Rotor-EZ on a pty, a paho client at
the broker's own port as the dashboard, and the MQTT-aware proxy on the bridge's path.

Now a guard: 415730e0 was taken back (the main connection keeps its keep-alive); any later
way of finding the main connection's dead path must pass it."""

from __future__ import annotations

import contextlib
from pathlib import Path

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.faults.behind_a_proxy import lanes_behind, main_up_after_a_doubt, said_offline
from tests.faults.test_review145_stop_carriers_keepalive import SlowPath
from tests.support.waiting import slow, wait_until

# 415730e0's DEAD_PATH_S (taken back): how long after a dead path or a lane's return a
# doubted main connection was made again at most
DEAD_PATH_S = 12


def test_a_stop_lane_stall_does_not_drop_a_main_connection_reading_a_backlog(
    tmp_path: Path,
) -> None:
    # a dashboard on the broker's own port; the bridge behind a SlowPath whose CONNACKs are prompt
    with lanes_behind(tmp_path, lambda port: SlowPath(port, 0.0)) as b:
        proxy, probe, rig, app = b.proxy, b.probe, b.rig, b.app
        main_id = rig.settings.mqtt.effective_client_id()
        mark = probe.mark()
        proxy.backlog(main_id)  # the main connection has a backlog to read
        proxy.hold(lane_client_id(rig.settings.mqtt))  # the stop lane's uplink stalls
        wait_until(lambda: not app.lane.connected.is_set(), slow(10), "the stop lane gone")
        wait_until(app.lane.connected.is_set, slow(15), "the stop lane back")

        def offline() -> list[str]:
            return said_offline(probe, mark)

        # the main connection's doubt is settled within DEAD_PATH_S of the lane's return
        main_up = main_up_after_a_doubt(probe, mark, app, slow(DEAD_PATH_S), proxy.released)
        assert not offline() and main_up, (
            f"a stall of the stop lane's uplink while the main connection read a backlog, "
            f"the broker healthy and the main connection's path fine: dashboards were shown "
            f"{offline()} offline; the main connection up: {main_up}"
        )


def test_a_lock_off_behind_a_backlog_stands_after_a_stop_lane_stall(tmp_path: Path) -> None:
    """The same spell, a lock OFF pressed in it: the lock lane's OFF is not carried out while
    the main connection is up (lastword.py rule 3), and the main connection's copy is in the
    backlog the bridge throws away with the connection."""
    # a dashboard on the broker's own port; the bridge behind a SlowPath whose CONNACKs are prompt
    with lanes_behind(tmp_path, lambda port: SlowPath(port, 0.0)) as b:
        proxy, probe, rig, app = b.proxy, b.probe, b.rig, b.app
        assert probe.publish("rotor/lock", "ON")  # the operator locks the rotator
        wait_until(lambda: rig.status("tower").locked, slow(10), "the lock ON carried out")
        main_id = rig.settings.mqtt.effective_client_id()
        proxy.backlog(main_id)  # the main connection has a backlog to read
        assert probe.publish("rotor/lock", "OFF")  # the work is done: OFF, at the broker
        proxy.hold(lane_client_id(rig.settings.mqtt))  # the stop lane's uplink stalls
        wait_until(lambda: not app.lane.connected.is_set(), slow(10), "the stop lane gone")
        wait_until(app.lane.connected.is_set, slow(15), "the stop lane back")
        with contextlib.suppress(AssertionError, TimeoutError):
            wait_until(
                lambda: not app.client.connected.is_set(),
                slow(DEAD_PATH_S),
                "the main connection given up",
            )
        proxy.released.set()  # the backlog read
        with contextlib.suppress(AssertionError, TimeoutError):
            wait_until(lambda: not rig.status("tower").locked, slow(15), "the lock OFF carried out")
        shown = [m.text for m in probe.on("rotor/lock/state")]
        assert not rig.status("tower").locked, (
            f"a lock OFF pressed while the main connection read a backlog, the stop lane's "
            f"uplink stalling a few seconds meanwhile, was lost: R/lock/state said {shown}"
        )
