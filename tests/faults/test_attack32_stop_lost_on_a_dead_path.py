"""Attack 32, with real mosquitto and a Rotor-EZ (with its stop express) or a Rot2Prog on a real
pty: the path under the bridge's connections goes dead without a word (a NAT or firewall that
lost its connection table in a router's reboot, a VPN or Wi-Fi link re-made under another
address, a proxy's failover that leaves the old streams hanging): no FIN, no RST, nothing
passes on them, while the broker takes new connections at once. A dashboard on the broker
still shows the rotator ``online`` (the broker waits 1.5 keep-alives before the bridge's will)
and the operator presses STOP.

Every connection that carries a stop (the main one, the stop lane, the stop express) noticed a
dead path only by its keep-alive: a PINGREQ after ``keepalive_s`` (30 s by default) of quiet,
then as long again for its answer, so the three came back 30 to 60 s after the path died (59 s
in a run; a STOP pressed meanwhile was lost with them, the rotor turning on to 300). The bridge
knew much sooner: 3 s after a heartbeat it published did not come back it said "the MQTT broker
holds up what the bridge publishes" and refused MQTT moves (docs/mqtt.md), yet it kept the
three dead connections.

Now it asks the broker on a connection of its own whether it answers, and, answered while its
own connection still hears nothing, remakes all three at once (interfaces/mqtt/client.py rule
21, heartbeat.py rule 12). What that promises, and what nothing can: a STOP the broker takes
while none of the bridge's connections is subscribed reaches none of them (a clean session: the
broker keeps nothing for a connection not back yet, connection.py rule 1), so a STOP pressed
3 s after the path died, before the quiet can be told from a healthy link's, is lost whatever
the bridge does (as one pressed in a broker restart's first seconds: docs/reliability.md). The
promise is the connections back within DEAD_PATH_S of the path dying, long before their
keep-alive, and a STOP pressed from then on stopping the rotor.

The path dies at the test's own proxy (tests/support/mqtt_proxy.py ``blackhole``); the dashboard
is on the broker's own port, as a phone on another network is. That the connections are back is
seen at the proxy: the broker's SUBACK to a new connection of each client id.
"""

from __future__ import annotations

import contextlib
import time
from pathlib import Path
from typing import Any

import pytest

from bridge.interfaces.mqtt.heartbeat import DEAD_PATH_S
from tests.support import Probe, retained_snapshot
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.tap import near_deg
from tests.support.waiting import slow, wait_until

KEEPALIVE_S = 30  # the bridge's default keep-alive: the dead connections' own end, 30-60 s on
PROMPT_S = 10.0  # a STOP reaches the controller within this (it takes well under a second)
TURN: dict[str, tuple[str, dict[str, Any], str, bool]] = {
    # a slow turn of each model (145 s, 180 s: under way past every deadline below, however
    # slowed), its target, whether the bridge runs its stop express
    "rotorez": ("rotorez", {"start_az_deg": 10, "speed_deg_s": 2.0}, "300", True),
    "rot2prog": ("rot2prog", {"start_az_deg": 10, "az_speed_deg_s": 1.0}, "190 0", False),
}
SHORT_DEG = 20.0  # a stopped rotor is this far from its target at least (not an arrival)


@pytest.mark.parametrize("model", sorted(TURN))
def test_a_stop_after_the_path_went_dead_reaches_the_rotor(tmp_path: Path, model: str) -> None:
    model_name, emu_options, target, express = TURN[model]
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = MqttProxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # a dashboard on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            rig.express = express  # the default where the model has a stop frame to copy
            rig.mqtt_extra = {"keepalive_s": KEEPALIVE_S}
            emu = rig.add("tower", model_name, emu=emu_options)
            app = rig.start()
            rig.ready("tower")
            wait_until(app.lane.connected.is_set, 10, "the stop lane up")
            ids = [app.settings.mqtt.effective_client_id(), app.lane.client_id]
            if express:
                wait_until(app.express.up.is_set, 10, "the stop express up")
                ids.append(app.express.client_id)
            probe.publish("rotor/target", target)  # a long turn
            emu.wait_for(lambda s: s.is_moving, slow(10))
            before = {cid: proxy.subacks.get(cid, 0) for cid in ids}
            proxy.blackhole()  # the path under all three connections dies without a word
            died = time.monotonic()
            shown = retained_snapshot(broker.port, "rotor/availability")
            assert shown.get("rotor/availability") == b"online", shown  # what a dashboard shows
            wait_until(
                lambda: all(proxy.subacks.get(cid, 0) > before[cid] for cid in ids),
                slow(DEAD_PATH_S),
                "the bridge's connections made again on a live path",
            )
            took = time.monotonic() - died
            assert took < KEEPALIVE_S, (
                f"the connections came back {took:.0f} s after the path died: their "
                "keep-alive's doing, not the bridge's"
            )
            assert emu.state().is_moving
            assert probe.publish("rotor/stop", "")  # the operator's STOP, at the broker
            with contextlib.suppress(AssertionError, TimeoutError):
                emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
            s = emu.state()
            short = not near_deg(s.az_deg, float(target.split()[0]), SHORT_DEG)
            assert not s.is_moving and short, (
                f"a STOP pressed {took:.0f} s after the path died, the bridge's connections "
                f"made again, did not stop the rotor: it turns on ({s.az_deg:.0f} deg)"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()


FROZEN_S = 12.0  # the broker's stall: the quiet judged (7 s at most) and a probe waited out (5 s)


def test_a_stop_a_frozen_broker_held_reaches_the_rotor_when_it_runs_on(rig: Rig) -> None:
    """The other side of the judgement: a broker frozen (SIGSTOP: an SD card writing its file,
    a VM paused) shows the bridge the same quiet as a dead path, but answers no new connection
    either, and the connections are kept: a STOP it took while frozen is delivered on them when
    it runs on. Remade during the stall (their old sessions ended by the takeover at the
    broker's return, the new ones subscribed after it routed the STOP), they would lose it."""
    rig.express = True
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
    app = rig.start()
    rig.ready("tower")
    wait_until(app.lane.connected.is_set, 10, "the stop lane up")
    wait_until(app.express.up.is_set, 10, "the stop express up")
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving, slow(10))
    rig.broker.pause()
    try:
        # the operator's STOP, into the frozen broker's socket (its PUBACK not waited for)
        rig.probe.client.publish("rotor/stop", "", qos=1)
        time.sleep(FROZEN_S)  # the broker frozen: the fault's length (not a deadline)
    finally:
        rig.broker.resume()
    emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
    assert not near_deg(emu.state().az_deg, 300, SHORT_DEG)
    assert app.client.redials == 0  # (the probe went unanswered: the connections were kept)
