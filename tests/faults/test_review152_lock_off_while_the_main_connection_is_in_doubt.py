"""Review 152 (cold review of 415730e0): on review 150's dead path (the path under the bridge's
connections dies without a word, the broker up throughout), the lock lane gives its connection
up for an unanswered ping and is subscribed again on a live path within STOP_DEAD_PATH_S; its
return puts the main connection's path in doubt (connection.py rule 6, ``prove_path``), and
the main connection is made again a few seconds later. A lock OFF the operator presses in
between reaches the lock lane, on its live path, and is not carried out: a lock OFF from the
lane waits for the main connection's copy while the main connection counts as up
(lastword.py rule 3), and the main connection, on the dead path, never gets one; its new
connection does not get it either (no replay). The rotator stays locked, though the one
connection that heard the word was already known to be on a live path and the main one's in
doubt. docs/reliability.md promises a lock OFF reaches the bridge again within DEAD_PATH_S of
the path dying; this one, pressed inside that time and read by the bridge, never takes effect.

The path dies at the test's own proxy (tests/support/mqtt_proxy.py ``blackhole``); the
dashboard is on the broker's own port.

Open: 415730e0 was taken back, and with the main connection's own keep-alive the lock OFF
waits for it 30 to 60 s and is lost the same way (review 150; docs/reliability.md, Limits)."""

from __future__ import annotations

import contextlib
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.faults.behind_a_proxy import lanes_behind
from tests.support.mqtt_proxy import MqttProxy
from tests.support.waiting import slow, wait_until

# 415730e0's DEAD_PATH_S (taken back): how long after a dead path or a lane's return a
# doubted main connection was made again at most
DEAD_PATH_S = 12


@pytest.mark.xfail(
    strict=True,
    reason="review-152 4: on a dead path, a lock OFF pressed once the lock lane is back on a "
    "live path, before the main connection in doubt is made again, never takes effect: the "
    "rotator stays locked",
)
def test_a_lock_off_read_on_the_lock_lane_back_on_a_live_path_takes_effect(
    tmp_path: Path,
) -> None:
    with lanes_behind(tmp_path, MqttProxy) as b:  # a dashboard on the broker's own port
        proxy, probe, rig, app = b.proxy, b.probe, b.rig, b.app
        assert probe.publish("rotor/lock", "ON")  # the operator locks the rotator
        wait_until(lambda: rig.status("tower").locked, slow(10), "the lock ON carried out")
        lock_lane = lane_client_id(rig.settings.mqtt, "lock")
        subacks = proxy.subacks.get(lock_lane, 0)
        proxy.blackhole()  # the path under every connection dies without a word
        wait_until(
            lambda: proxy.subacks.get(lock_lane, 0) > subacks,
            slow(15),
            "the lock lane subscribed again on a live path",
        )
        main_up = app.client.connected.is_set()  # (still counted up, on the dead path)
        assert probe.publish("rotor/lock", "OFF")  # the work is done: OFF, at the broker
        with contextlib.suppress(AssertionError, TimeoutError):
            wait_until(
                lambda: not rig.status("tower").locked,
                slow(DEAD_PATH_S + 5),
                "the lock OFF carried out",
            )
        shown = [m.text for m in probe.on("rotor/lock/state")]
        assert not rig.status("tower").locked, (
            f"a lock OFF pressed once the lock lane was back on a live path (the main "
            f"connection counted up then: {main_up}) never took effect: R/lock/state said "
            f"{shown}; the main connection up now: {app.client.connected.is_set()}"
        )
