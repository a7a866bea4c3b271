"""Review 121 (a regression of 9b6b651c): a busy uplink of ~12 s under the main connection and
the stop lane alike (a cellular modem's FIFO buffer filled by an upload: every flow's packets
wait their turn) now remakes the stop lane, whose kept session hands over the STOP the lane had
already read and carried out, and that old copy drops the target the operator sent after it.

The lane's keep-alive is 5 s (connection.py rule 22): its PINGREQ waits in the uplink, so it
gives its path up and connects again (a new flow passes). The broker, which never got the
lane's PUBACK of the STOP (it waits in the same uplink), sends the STOP again on the new
connection, before its SUBACK. The copy is dropped only when the main connection "had it"
(``has_all``): its heartbeats coming back, which they do not behind a busy uplink
(``broker_late``). So the copy is carried out as a new STOP: the target sent after the STOP,
waiting under the lane's hold for the main connection's marker, is dropped with nothing said on
R/error, and the rotor stays where the STOP left it. On the parent (a 30 s keep-alive, a clean
session) nothing is remade, and the target turns the rotor as soon as the uplink drains;
with the copy dropped by hand (``has_all`` always yes) the same happens on today's code.

Real mosquitto, the test's proxy (its ``hold`` of what the main connection and the stop lane
send, let go after the busy spell), a Rotor-EZ on a real pty; the operator on the broker's
own port.
"""

from __future__ import annotations

import time
from pathlib import Path

from tests.faults.behind_a_proxy import bridge_behind
from tests.support.mqtt_proxy import MqttProxy
from tests.support.waiting import slow

BUSY_S = 12.0  # the uplink's busy spell: past the lane's 5 s keep-alive and its 5 s wait
NEW_DEG = 60.0  # the target sent after the STOP (the rotor near 10, 2 deg/s)


def test_a_target_after_a_stop_survives_a_busy_uplink(tmp_path: Path) -> None:
    with bridge_behind(tmp_path, MqttProxy) as b:
        main_id = b.app.settings.mqtt.effective_client_id()
        lane = b.app.lane.client_id
        before = b.proxy.subacks.get(lane, 0)
        b.probe.publish("rotor/target", "300")
        b.emu.wait_for(lambda s: s.is_moving, slow(10))
        mark = b.probe.mark()
        for cid in (main_id, lane):  # the uplink busy: what both send waits its turn
            b.proxy.hold(cid)
        try:
            assert b.probe.publish("rotor/stop", "")
            b.emu.wait_for(lambda s: not s.is_moving, slow(5))
            assert b.probe.publish("rotor/target", f"{NEW_DEG:g}")  # the operator's last word
            time.sleep(BUSY_S)  # the busy spell: the fault's length (not a deadline)
        finally:
            for cid in (main_id, lane):
                b.proxy.release(cid)
        remade = b.proxy.subacks.get(lane, 0) - before
        try:
            moved = b.emu.wait_for(lambda s: s.is_moving, slow(10)).is_moving
        except TimeoutError:
            moved = False
        said = [m.text for m in b.probe.messages[mark:] if m.topic == "rotor/error"]
        assert moved, (
            f"the target {NEW_DEG:g} sent after the STOP never turned the rotor once a "
            f"{BUSY_S:g} s busy uplink drained (the stop lane remade {remade} time(s), its kept "
            f"session's copy of the STOP carried out again); R/error said: {said}"
        )
