"""Review 112: a main connection whose uplink is merely busy (what it sends queued, the broker
healthy and every other flow passing) is judged a dead path (interfaces/mqtt/client.py rule
21): every connection of the bridge is remade, and dashboards see the bridge go ``offline``.

The probe is a new flow. Behind a saturated uplink with fair queueing (fq_codel, the default
on Linux and on most home and cellular routers), a new connection's few packets go ahead of
the main connection's queue: the probe is answered at once, while the main connection's
heartbeat waits its turn and nothing comes back to it; the verdict is "dead", and the main
connection, both lanes and the express are ended and made again. The takeover at the broker
publishes the main connection's will: ``B/bridge/state`` says ``offline`` to every dashboard
(then ``online``), the log says a router lost its table, and the stop lane and express, whose
flows were fine, are off the broker for a round trip. Left alone (as before 68346e15) the
queue drains and nothing is remade.

The busy uplink is the test's proxy's ``hold`` (what the main connection sends kept, in
order, and let go), its other flows and new ones passing; the dashboard is on the broker's
own port.
"""

from __future__ import annotations

import time
from pathlib import Path

from tests.faults.behind_a_proxy import KEEPALIVE_S, bridge_behind
from tests.support.mqtt_proxy import MqttProxy
from tests.support.waiting import slow, wait_until

BUSY_S = 12.0  # the uplink's busy spell: the quiet judged (7 s at most) and a probe answered


def test_a_busy_uplink_does_not_remake_the_connections(tmp_path: Path) -> None:
    with bridge_behind(tmp_path, MqttProxy) as b:
        proxy = b.proxy
        probe = b.probe
        app = b.app
        main_id = app.settings.mqtt.effective_client_id()
        ids = [main_id, app.lane.client_id, app.express.client_id]
        before = {cid: proxy.subacks.get(cid, 0) for cid in ids}
        mark = probe.mark()
        proxy.hold(main_id)  # the main connection's uplink busy
        try:
            time.sleep(BUSY_S)  # the busy spell: the fault's length (not a deadline)
        finally:
            proxy.release(main_id)
        # the queue drained: the bridge says its broker no longer holds anything up
        wait_until(
            lambda: (
                any(
                    m.topic == "rotor/bridge/info" and b'"problems":[]' in m.payload
                    for m in probe.messages[mark:]
                )
                and not app.client.problems
            ),
            slow(KEEPALIVE_S),
            "the bridge's heartbeats back",
        )
        shown = [m.payload for m in probe.messages[mark:] if m.topic == "rotor/bridge/state"]
        remade = [cid for cid in ids if proxy.subacks.get(cid, 0) > before[cid]]
        assert b"offline" not in shown and not remade, (
            f"a {BUSY_S:g} s busy spell of the main connection's uplink, the broker healthy: "
            f"dashboards were shown the bridge {shown}, connections remade: {remade}"
        )
