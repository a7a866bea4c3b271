"""Review 148 (cold review of 1998b9a5 and 1d44d710): a stop's carrier now gives its
connection up when a ping goes unanswered 2 s (connection.py rule 6, paho_client.py
``ping_within``). An uplink that stalls a few seconds (Wi-Fi, a saturated upload: the bytes
held, not lost) now ends the stop lane, which is away for its reconnect's first wait and
more; a STOP pressed then reaches the main connection only, behind whatever it has to read
first: the flood of targets the lane exists to go around (lane.py). With the setting's
keep-alive (30 s) the same stall ended nothing, and the lane, whose downlink never stalled,
carried the STOP at once.

Real parts: mosquitto, the bridge in-process, an emulated Rotor-EZ on a pty, a paho client at
the broker's own port as the dashboard, and the MQTT-aware proxy on the bridge's path: what the
stop lane sends held (its uplink stalls; a new connection passes), and what the broker sends
the main connection held (its backlog: review 145's ``SlowPath``)."""

from __future__ import annotations

import contextlib
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.faults.behind_a_proxy import TOWER, lanes_behind
from tests.faults.test_review145_stop_carriers_keepalive import SlowPath
from tests.support.tap import near_deg
from tests.support.waiting import slow, wait_until

TARGET = "300"  # from 10 deg at 2 deg/s: 145 s under way, past every deadline below
SHORT_DEG = 20.0  # a stopped rotor is this far from its target at least
PROMPT_S = 10.0  # a STOP reaches the controller within this (it takes well under a second)
STALL_S = 10.0  # the lane's uplink stalls this long at most (the STOP is pressed within it)


@pytest.mark.xfail(
    strict=True,
    reason="review-148 1: a STOP pressed during a few seconds' stall of the bridge's uplink, "
    "while the main connection reads a backlog, waits behind the backlog: the 2 s ping ended the "
    "stop lane, whose downlink was fine, and the rotor turns on",
)
def test_a_stop_during_an_uplink_stall_takes_the_lane_not_the_backlog(tmp_path: Path) -> None:
    # a dashboard on the broker's own port; the bridge behind a SlowPath whose CONNACKs are prompt
    with lanes_behind(tmp_path, lambda port: SlowPath(port, 0.0), emu=TOWER, lock_lane=False) as b:
        proxy, probe, rig, emu, app = b.proxy, b.probe, b.rig, b.emu, b.app
        probe.publish("rotor/target", TARGET)  # a long turn
        emu.wait_for(lambda s: s.is_moving, slow(10))
        proxy.backlog(rig.settings.mqtt.effective_client_id())  # the main one's reading
        proxy.hold(lane_client_id(rig.settings.mqtt))  # the lane's uplink stalls
        # the operator presses STOP during the stall: once the lane let its connection go
        # (2 s ping, 2 s for its answer), or STALL_S into it if it never does
        with contextlib.suppress(AssertionError, TimeoutError):
            wait_until(lambda: not app.lane.connected.is_set(), STALL_S, "the lane gone")
        gone = not app.lane.connected.is_set()
        assert probe.publish("rotor/stop", "")  # the operator's STOP, at the broker
        with contextlib.suppress(AssertionError, TimeoutError):
            emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
        s = emu.state()
        assert not s.is_moving and not near_deg(s.az_deg, float(TARGET), SHORT_DEG), (
            f"a STOP pressed during a stall of the bridge's uplink (the stop lane gone "
            f"meanwhile: {gone}), the main connection reading a backlog, did not stop the "
            f"rotor: it turns on ({s.az_deg:.0f} deg)"
        )
