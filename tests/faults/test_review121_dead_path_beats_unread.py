"""Review 121: attack 32's dead path, on a broker whose ACL keeps the bridge from reading its
own heartbeats back (a setup docs/mqtt.md supports: said on B/bridge/info, "stalled moves
carried out as before"): the STOP pressed after the path died is lost, and the rotor turns on.

1f2e23a9 drops a stop lane's handed-over copy when the main connection "had it" (``has_all``,
app.py ``_main_had_all``): its command topics without a break since the lane's previous
connection was accepted, and ``broker_late()`` None, taken for "its path is alive now". But
``broker_late()`` is None too when no beat of the connection has ever come back (heartbeat.py
``late``: "nothing to judge by"). With the path dead under every connection, the main
connection has not noticed (its keep-alive is the setting's, 30 s), so it still counts as
subscribed without a break; the stop lane, back 5-10 s after the death, is handed the STOP
by its kept session and drops it as a copy the main connection had. The main connection
never had it: when it gives its path up, 30-60 s later, it starts clean and the STOP is gone.

Attack 32's own test, with a mosquitto ACL denying the heartbeat topic (as
tests/mqtt/test_broker_late_acl.py does): a Rot2Prog (no stop express: the lane alone
carries the STOP back). Without the ACL the same test passes (attack 32's test). The lock lane
the same way: a lock ON pressed after the death (before climbing the tower) is dropped, the
rotor turns on and the rotator is never locked.
"""

from __future__ import annotations

import contextlib
import time
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.connection import STOP_RECONNECT_MAX_S
from bridge.interfaces.mqtt.heartbeat import UNREAD_S
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.tap import near_deg
from tests.support.waiting import slow, wait_until

BEAT = "rotor/bridge/heartbeat"
PRESSED_S = STOP_RECONNECT_MAX_S + 1.0  # the STOP pressed this long after the path died
PROMPT_S = 20.0  # well past the ~12 s a dead path costs a STOP (connection.py rule 22)
TARGET = "190 0"  # a slow turn (180 s at 1 deg/s): under way past every deadline here
SHORT_DEG = 20.0  # a stopped rotor is this far from its target at least (not an arrival)
WORDS = {"stop": ("rotor/stop", ""), "lock": ("rotor/lock", "ON")}  # each stops a turn


@pytest.mark.parametrize("word", sorted(WORDS))
def test_a_stop_after_the_path_went_dead_reaches_the_rotor_with_the_beats_unread(
    tmp_path: Path, word: str
) -> None:
    topic, payload = WORDS[word]
    acl = tmp_path / "acl"
    acl.write_text(f"topic readwrite rotor/#\ntopic deny {BEAT}\n")
    # started as root, mosquitto would become user "mosquitto", who cannot read pytest's tmp
    conf = f"allow_anonymous true\nacl_file {acl}\nuser root"
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf).start()
    proxy = MqttProxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # a dashboard on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            emu = rig.add("tower", "rot2prog", emu={"start_az_deg": 10, "az_speed_deg_s": 1.0})
            app = rig.start()
            rig.ready("tower")
            for lane in (app.lane, app.lock_lane):
                wait_until(lane.connected.is_set, slow(10), f"the {lane.kind} lane up")
            wait_until(
                lambda: any(BEAT in p for p in app.client.problems),
                slow(3 * UNREAD_S),
                "the beats said unread (B/bridge/info)",
            )
            probe.publish("rotor/target", TARGET)  # a long turn
            emu.wait_for(lambda s: s.is_moving, slow(10))
            proxy.blackhole()  # the path under every connection dies without a word
            time.sleep(PRESSED_S)  # the user's hand: the scenario's timing, not a wait
            assert emu.state().is_moving
            assert probe.publish(topic, payload)  # the operator's STOP (lock ON), at the broker
            with contextlib.suppress(AssertionError, TimeoutError):
                emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
            s = emu.state()
            short = not near_deg(s.az_deg, float(TARGET.split()[0]), SHORT_DEG)
            assert not s.is_moving and short, (
                f"a {word} pressed {PRESSED_S:g} s after the path died (the heartbeat topic "
                f"denied by the ACL) did not stop the rotor within {PROMPT_S:g} s: it turns on "
                f"({s.az_deg:.0f} deg); the stop lane up again: {app.lane.connected.is_set()}, "
                f"the lock lane: {app.lock_lane.connected.is_set()}"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()
