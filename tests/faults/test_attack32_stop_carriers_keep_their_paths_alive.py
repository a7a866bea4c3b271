"""Attack 32's dead-path fix (interfaces/mqtt/connection.py rule 22), its other side: the stop
carriers (the stop and lock lanes, the stop express) ask the broker for a keep-alive of
STOP_KEEPALIVE_S (5 s), so mosquitto drops one that sends no packet for 1.5 times that, and
each gives its own path up when a PINGREQ is not answered within as long again. A quiet stop
carrier on a healthy path, the bridge busy on its serial line (a Rotor-EZ polled throughout),
must keep the one connection it has: its pings go out in time from its own network thread, and
the broker's answers come back in time; not one connection is remade (its SUBACKs counted at
the proxy, as review 112's busy uplink test counts them).
"""

from __future__ import annotations

import time
from pathlib import Path

from bridge.interfaces.mqtt.connection import STOP_KEEPALIVE_S
from tests.faults.behind_a_proxy import bridge_behind
from tests.support.mqtt_proxy import MqttProxy

QUIET_S = 3 * STOP_KEEPALIVE_S  # twice the broker's 1.5 keep-alives, and the bridge's own 2


def test_quiet_stop_carriers_keep_their_connections_on_a_healthy_path(tmp_path: Path) -> None:
    with bridge_behind(tmp_path, MqttProxy) as b:
        app = b.app
        ids = [app.lane.client_id, app.lock_lane.client_id, app.express.client_id]
        before = {cid: b.proxy.subacks.get(cid, 0) for cid in ids}
        assert all(before.values()), before  # each connection known at the proxy
        time.sleep(QUIET_S)  # nothing on the stop topics: the quiet the test is about
        remade = [cid for cid in ids if b.proxy.subacks.get(cid, 0) > before[cid]]
        assert not remade and app.lane.connected.is_set() and app.express.up.is_set(), (
            f"quiet for {QUIET_S:g} s on a healthy path, the serial line busy: the stop "
            f"carriers remade {remade}; the stop lane up: {app.lane.connected.is_set()}, "
            f"the express up: {app.express.up.is_set()}"
        )
