"""Attack 23, with real mosquitto (persistence on, as Debian ships it) and a Rotor-EZ on a real
pty: a broker down for half a minute or more (its host rebooted, an upgrade that took its
time) comes back to a bridge in its reconnect back-off, and a STOP sent then is lost.

docs/reliability.md: a broker that is down is "waited for and reconnected to, forever, with
exponential back-off (1 s doubling to 30 s)". Every connection of the bridge (the main one,
the stop lane, the stop express: interfaces/mqtt/connection.py) tries again on that back-off
alone, so after 33 s without a broker the next try is at about 61 s: for some 28 s after the
broker is back nothing of the bridge's is subscribed. The broker meanwhile shows what it kept
(``R/availability`` ``online``: a broker's own shutdown sends no last will), so the dashboard
offers STOP, and the STOP it sends reaches nobody (a clean session keeps nothing for later):
the rotor turns on to its old target (from 217 to 300 in a run; the bridge reconnected 28 s
after the broker was back).

Now the connections that carry stops back off STOP_RECONNECT_MAX_S at most (connection.py rule
6): the STOP is pressed that long after the broker is back, plus a connect's time (PRESSED_S:
the scenario, the user's hand, not a wait for the bridge). A STOP sent sooner than that can
still reach nobody while the broker keeps nothing for the lane (its clean session:
docs/reliability.md, Limits); under the old back-off this STOP came 25 s before the bridge did.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from bridge.interfaces.mqtt.connection import STOP_RECONNECT_MAX_S
from tests.support import Probe, retained_snapshot
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

DOWN_S = (
    33.0  # the broker away: the fault's length, past five tries of the back-off (not a deadline)
)
SPEED_DEG_S = 6.0  # a turn from 10 to 300 lasts 48 s: it is under way throughout the outage
PROMPT_S = 3.0  # a STOP reaches the controller within this (it takes well under a second)
COAST_DEG = 5.0  # what a stopped rotor may still turn, and a reading's jitter
PRESSED_S = STOP_RECONNECT_MAX_S + 1.0  # the STOP pressed this long after the broker is back


class _KeepingMosquitto(Mosquitto):
    """mosquitto that keeps its retained messages across a restart (Debian's default)."""

    def config(self) -> str:
        user = "user root\n" if os.geteuid() == 0 else ""  # (it drops to 'mosquitto' otherwise)
        return (
            f"listener {self.port} {self.host}\npersistence true\n"
            f"persistence_location {self.workdir}/\n{user}allow_anonymous true\n"
        )


def test_a_stop_sent_once_the_broker_is_back_stops_the_rotor(tmp_path: Path) -> None:
    broker = _KeepingMosquitto(tmp_path / "mosquitto")
    broker.start()
    probe = Probe(broker.port)
    try:
        with Rig(tmp_path, broker, probe) as rig:
            rig.express = True  # the default: every way a stop comes in
            emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10, "speed_deg_s": SPEED_DEG_S})
            rig.start_process()
            rig.ready("tower", timeout_s=slow(40))
            probe.publish("rotor/target", "300")
            emu.wait_for(lambda s: s.is_moving and s.az_deg > 15, slow(10))
            broker.stop()
            time.sleep(DOWN_S)  # the broker away: the fault's length (not a deadline)
            broker.start()
            back_t = time.monotonic()
            wait_until(probe.client.is_connected, 10, "the dashboard back on the broker")
            probe.caught_up()
            shown = retained_snapshot(broker.port, "rotor/#")
            assert shown.get("rotor/availability") == b"online", shown  # what a dashboard shows
            assert emu.state().is_moving
            # the user's hand: the scenario's timing, not a wait for the bridge (docstring)
            time.sleep(max(0.0, back_t + slow(PRESSED_S) - time.monotonic()))
            assert emu.state().is_moving
            at_stop = emu.state().az_deg
            assert probe.publish("rotor/stop", "STOP")
            rest = emu.wait_for(lambda s: not s.is_moving, slow(60))
            stops = [f for f in emu.log() if f.outcome == "stop"]
            assert rest.az_deg - at_stop < SPEED_DEG_S * PROMPT_S + COAST_DEG, (
                f"the STOP sent at {at_stop:.0f}, once the broker was back and the rotator shown "
                f"online, did not stop the rotor: it turned on to {rest.az_deg:.0f} "
                f"({len(stops)} stop frames on the wire)"
            )
    finally:
        probe.close()
        broker.stop()
