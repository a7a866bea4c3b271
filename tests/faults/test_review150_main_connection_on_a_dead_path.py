"""Review 150, with real mosquitto and a Rotor-EZ on a real pty: the path under the bridge's
connections dies without a word (attack 32's router that lost its connection table), the broker
up throughout. Since attack 32 the stop and lock lanes ping every 2 s and are back on a live
path within STOP_DEAD_PATH_S, but the main connection, which carries every other command
(targets, the lock OFF, presets, options), kept its keep-alive of 30 s: it heard nothing for 30
to 60 s, while a dashboard showed the rotator ``online``, and a target or a lock OFF pressed then
was lost (the lock lane's words are not acted on while the main connection counts as up).

Now a lane accepted again after it gave a connection up for an unanswered ping puts the main
connection's path in doubt (connection.py rule 6, ``prove_path``): the broker answers new
connections, so the main one pings within STOP_KEEPALIVE_S and, unanswered, is made again; it
is back within DEAD_PATH_S. A broker that freezes answers no lane either, so the main
connection still rides a frozen broker out (review 148's SIGSTOP runs).

The path dies at the test's own proxy (tests/support/mqtt_proxy.py ``blackhole``); the dashboard
is on the broker's own port, as a phone on another network is."""

from __future__ import annotations

import contextlib
import time
from pathlib import Path

from bridge.interfaces.mqtt.connection import DEAD_PATH_S
from tests.support import Probe, retained_snapshot
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.tap import near_deg
from tests.support.waiting import slow, wait_until

PRESSED_S = DEAD_PATH_S + 1.0  # the command pressed this long after the path died
PROMPT_S = 10.0  # a target starts the rotor within this (it takes well under a second)
START_AZ, TARGET_AZ = 10.0, 60.0


def test_a_target_pressed_once_the_main_connection_could_find_a_dead_path_turns_the_rotor(
    tmp_path: Path,
) -> None:
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = MqttProxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # a dashboard on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            emu = rig.add("tower", "rotorez", emu={"start_az_deg": START_AZ, "jitter_deg": 0})
            app = rig.start()
            rig.ready("tower")
            wait_until(app.lane.connected.is_set, 10, "the stop lane up")
            wait_until(app.lock_lane.connected.is_set, 10, "the lock lane up")
            proxy.blackhole()  # the path under every connection dies without a word
            # the user's hand: the scenario's timing, not a wait for the bridge (docstring)
            time.sleep(PRESSED_S)
            shown = retained_snapshot(broker.port, "rotor/availability")
            assert shown.get("rotor/availability") == b"online", shown  # what a dashboard shows
            assert probe.publish("rotor/target", f"{TARGET_AZ:g}")  # at the broker
            with contextlib.suppress(AssertionError, TimeoutError):
                emu.wait_for(
                    lambda s: s.is_moving or near_deg(s.az_deg, TARGET_AZ, 2), slow(PROMPT_S)
                )
            s = emu.state()
            assert s.is_moving or near_deg(s.az_deg, TARGET_AZ, 2), (
                f"a target pressed {PRESSED_S:g} s after the path died, the broker up "
                f"throughout, never reached the rotor ({s.az_deg:.0f} deg); the main connection "
                f"up: {app.client.connected.is_set()}, the lanes: {app.lane.connected.is_set()}, "
                f"{app.lock_lane.connected.is_set()}"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()
