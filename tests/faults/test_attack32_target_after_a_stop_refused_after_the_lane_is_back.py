"""Attack 32, with real mosquitto and a Rotor-EZ or a Rot2Prog on a real pty: the stop lane comes
back alone (its connection dropped: a NAT's idle timer, a broker's per-client limit, a proxy's
restart of that one stream), and the operator presses STOP right after the lane's SUBACK, then
sends a new target. The target, published after the STOP, is refused as "published before a
STOP ... that the stop connection carried out first"; the rotor stays where it stopped.

lastword.py rule 9: a halt the main connection reads before the lane's ``lane_subscribed``
marker is back does not count as the copy of the lane's halts. Rule 2: a move the main
connection reads while the lane's hold lasts and before the copy is refused as older. So when
the STOP reaches the broker after the lane's SUBSCRIBE and before that marker (the marker goes
out on the main connection, behind whatever it is sending), the main connection's own copy of
the STOP, read before the target, counts for nothing, and the target that follows it is taken
for one published before the STOP. The same target, with the marker back first, turns the rotor
(checked by hand: hold the main connection's bytes the same way with the lane left alone, and
the target is obeyed).

The moment is placed by a proxy of the test's own between the bridge and the broker that knows
each connection by the client id of its CONNECT: it drops the lane's connection, and holds what
the main connection sends (its marker) until the STOP and the target are published, as a busy
uplink would; the STOP is published once the broker has sent the lane its SUBACK.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

MODELS: dict[str, tuple[dict[str, float], str, Callable[[float], str]]] = {
    # model: its emulator's options (a slow turn), the target's payload
    "rotorez": ({"start_az_deg": 10, "speed_deg_s": 10.0}, "rotorez", lambda az: f"{az:g}"),
    "rot2prog": ({"start_az_deg": 10, "az_speed_deg_s": 10.0}, "rot2prog", lambda az: f"{az:g} 0"),
}
FAR_DEG = 300.0  # the first turn's target: under way when the lane is dropped
NEW_DEG = 100.0  # the target sent after the STOP


@pytest.mark.parametrize("model", sorted(MODELS))
def test_a_target_after_a_stop_right_after_the_lanes_suback_turns_the_rotor(
    tmp_path: Path, model: str
) -> None:
    emu_options, model_name, payload = MODELS[model]
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = MqttProxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # a dashboard on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            emu = rig.add("tower", model_name, emu=emu_options)
            app = rig.start()
            rig.ready("tower")
            mqtt = rig.settings.mqtt
            main, lane = mqtt.effective_client_id(), lane_client_id(mqtt)
            wait_until(app.lane.connected.is_set, 10, "the stop lane up")
            probe.publish("rotor/target", payload(FAR_DEG))
            emu.wait_for(lambda s: s.is_moving, slow(10))
            subacks = proxy.subacks.get(lane, 0)
            proxy.hold(main)  # its bytes (the lane's marker among them) wait: a busy uplink
            proxy.drop(lane)  # the lane's connection lost; it comes back on its own
            wait_until(lambda: proxy.subacks.get(lane, 0) > subacks, 10, "the lane's SUBACK")
            assert probe.publish("rotor/stop", "")  # the operator's STOP, at the broker
            emu.wait_for(lambda s: not s.is_moving and not s.in_brake_delay, slow(10))
            assert probe.publish("rotor/target", payload(NEW_DEG))  # then a new target
            proxy.release(main)
            refused = lambda: [m.text for m in probe.on("rotor/error") if "refused" in m.text]  # noqa: E731
            wait_until(
                lambda: emu.state().is_moving or refused(), 10, "the target carried out or refused"
            )
            assert not refused(), (
                f"the target {NEW_DEG:g} sent after the STOP was refused, the rotor left at "
                f"{emu.state().az_deg:.0f}: {refused()}"
            )
            rig.arrived("tower", NEW_DEG)
    finally:
        probe.close()
        proxy.close()
        broker.stop()


def test_a_lock_off_after_a_lock_on_right_after_the_lock_lanes_suback_unlocks(
    tmp_path: Path,
) -> None:
    """The lock lane's twin: the same window (the lock lane back alone, its ``lane_subscribed``
    marker not yet at the broker), a lock ON pressed in it, then OFF. The OFF is carried out
    (``R/lock/state`` OFF), and some 50 ms later, as the main connection's markers come back,
    the lock is set again (``R/lock/state`` ON), nothing said on ``R/error``: the operator's
    last word was OFF, and the next target is refused as locked. (With the stop express on and
    half a second between the two, the OFF was refused instead, "a lock ON that may have been
    published after it came on the stop connection".) docs/mqtt.md says as much of a lock ON
    only the stop express heard, not of the lock lane. The same ON and OFF without the lock
    lane's reconnect unlock (an attack run: ten in a row). The target sent after the OFF is
    neither carried out nor refused: nothing on ``R/error``, no long hold on ``B/bridge/info``
    25 s later (an attack run)."""
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = MqttProxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # a dashboard on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10})
            app = rig.start()
            rig.ready("tower")
            mqtt = rig.settings.mqtt
            main, lane = mqtt.effective_client_id(), lane_client_id(mqtt, "lock")
            wait_until(app.lock_lane.connected.is_set, 10, "the lock lane up")
            subacks = proxy.subacks.get(lane, 0)
            proxy.hold(main)  # its bytes (the lane's marker among them) wait: a busy uplink
            proxy.drop(lane)  # the lock lane's connection lost; it comes back on its own
            wait_until(lambda: proxy.subacks.get(lane, 0) > subacks, 10, "the lane's SUBACK")
            assert probe.publish("rotor/lock", "ON")  # the operator's lock ON, at the broker
            wait_until(lambda: rig.status("tower").locked, 10, "the lock ON carried out")
            assert probe.publish("rotor/lock", "OFF")  # then OFF: the work is done
            proxy.release(main)
            said = lambda: [m.text for m in probe.on("rotor/error") if "refused" in m.text]  # noqa: E731
            wait_until(lambda: said() or not rig.status("tower").locked, 10, "the OFF handled")
            probe.publish("rotor/target", f"{NEW_DEG:g}")  # the next target
            with contextlib.suppress(AssertionError):  # (judged below, with what was said)
                wait_until(lambda: said() or emu.state().is_moving, 10, "the target taken")
            shown = [m.text for m in probe.on("rotor/lock/state")]
            assert not said() and shown[-1] == "OFF" and emu.state().is_moving, (
                f"the lock OFF sent after the lock ON did not stand: R/lock/state said {shown}; "
                f"the target {NEW_DEG:g} after it: the rotor moving {emu.state().is_moving}, "
                f"R/error {said()}"
            )
            rig.arrived("tower", NEW_DEG)
    finally:
        probe.close()
        proxy.close()
        broker.stop()
