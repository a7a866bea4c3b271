"""Review 121: the stop lane comes back from a dead path with the STOP in its kept session
(interfaces/mqtt/connection.py rule 22) and drops it as "a copy the main connection had",
while the main connection is still seconds behind a backlog of targets and has not read it:
the STOP reaches the rotor 10+ s later, when the main connection gets to it.

1f2e23a9's ``has_all`` (app.py ``_main_had_all``) asks whether the main connection has been
subscribed without a break since the lane's previous connection and whether its heartbeats
come back in time (``broker_late()`` None). Neither says that it has READ the copy: a main
connection behind a backlog (a burst of targets: its socket never quiet, so never "late":
docs/mqtt.md, "Being behind is not being held up") has the STOP still queued behind the
targets. The stop lane exists for exactly this (lane.py: behind no target); its copy,
dropped, leaves the STOP behind the backlog. With the drop off (``has_all`` None) the STOP
reaches the rotor within moments of the lane's return (2.7 s after the STOP in a hand run,
16.2 s with the drop, 60,000 targets ahead of it).

A Rot2Prog (no stop express: the lane and the main connection carry the STOP), real mosquitto,
the test's proxy (its ``blackhole`` of the stop lane's client id); the operator and the burst
on the broker's own port.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

BURST = 60_000  # targets published ahead of the STOP (QoS 0, as an automation's burst)
BACK_S = 30.0  # the stop lane given up (5-10 s) and made again, the burst's publishing aside
PROMPT_S = 3.0  # the lane's copy read and carried out once the lane is back (well under 1 s)
TARGET = "190 0"  # a slow turn (180 s at 1 deg/s)


def test_the_lanes_kept_stop_is_not_dropped_while_the_main_connection_is_behind(
    tmp_path: Path,
) -> None:
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = MqttProxy(broker.port)
    probe = Probe(broker.port, "rotor/#")
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            emu = rig.add("tower", "rot2prog", emu={"start_az_deg": 10, "az_speed_deg_s": 1.0})
            app = rig.start()
            rig.ready("tower")
            lane = app.lane.client_id
            wait_until(app.lane.connected.is_set, slow(10), "the stop lane up")
            before = proxy.subacks.get(lane, 0)
            probe.publish("rotor/target", TARGET)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            proxy.blackhole(lane)  # the stop lane's path dies alone
            for _ in range(BURST):  # an automation's burst: the main connection falls behind
                probe.client.publish("rotor/target", "191 0", qos=0)
            assert probe.publish("rotor/stop", "")  # the operator's STOP, behind the burst
            wait_until(lambda: proxy.subacks.get(lane, 0) > before, slow(BACK_S), "lane back")
            with contextlib.suppress(AssertionError, TimeoutError):
                emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
            s = emu.state()
            behind = app.client.broker_late()
            assert not s.is_moving, (
                f"the stop lane came back with the STOP in its kept session, and the rotor "
                f"still turns {PROMPT_S:g} s later ({s.az_deg:.0f} deg): the copy dropped as "
                f"one the main connection had, which is still behind {BURST} targets "
                f"(broker_late: {behind})"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()
