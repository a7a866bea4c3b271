"""Review 114: d8136809 lets a lock OFF a connection of the lock's read order the stop
express's ``early`` lock ON before it (halts.py ``read_since``: "off"), so that lock ON is not
set. The lock lane notes every live lock OFF it reads (``lane_halt``), before anything judges
it; with the main connection up, the main connection judges it, and refuses it when its stamp
says a link held it up (service.py rule 9: sent long ago, older than its expiry; so sent before
the lock ON). The OFF is refused, said on R/error, the lock was never turned OFF by it; yet
its note makes the bridge drop the lock ON only the express read (a second press after a
broker restart, its sync word not yet back): the rotator stays unlocked, and the next target
turns the rotor with someone on the tower.

Real mosquitto, the bridge in this process, the express in its own, a Rotor-EZ on a real pty;
the gate of tests/integration/test_stop_before_the_express_words_are_back.py, as in
tests/integration/test_review108_early_lock_after_off.py.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from bridge.interfaces.mqtt.express import express_client_id
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.lane import lane_client_id
from tests.integration.express_gate import OPEN, WORDS, Gate
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until


@pytest.fixture
def broker_conf(tmp_path: Path) -> str:
    (tmp_path / "words.acl").write_text(OPEN)
    return f"allow_anonymous true\nacl_file {tmp_path / 'words.acl'}\nuser root"


def _stale_lock_off(port: int) -> None:
    """A lock OFF a link held up: stamped (MQTT 5 user properties) as sent 100 s ago with a
    5 s expiry."""
    client = paho.Client(
        CallbackAPIVersion.VERSION2, client_id="review114-link", protocol=paho.MQTTv5
    )
    client.connect("127.0.0.1", port)
    client.loop_start()
    try:
        props = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
        props.UserProperty = Stamp.of(time.time() - 100, 5).properties()
        info = client.publish("rotor/lock", "OFF", qos=1, properties=props)
        info.wait_for_publish(slow(5))
        assert info.is_published()
    finally:
        client.disconnect()
        client.loop_stop()


def test_an_early_lock_on_is_set_after_a_lock_off_the_bridge_refused(
    tmp_path: Path, broker: Mosquitto, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.DEBUG, logger="bridge.interfaces.mqtt.express")
    gate = Gate(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, gate, probe) as rig:
            rig.express = True
            emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
            settings = rig.settings.mqtt
            gate.held_id = express_client_id(settings)
            app = rig.start()
            rig.ready("tower")
            wait_until(app.express.up.is_set, 10, "the express up")
            wait_until(lambda: "tower" in app.express.held, 10, "the express holds the port")
            bridge_ids = {
                settings.effective_client_id(),
                lane_client_id(settings),
                lane_client_id(settings, "lock"),
            }
            gate.refused |= bridge_ids  # the bridge's connections back after the lock ON
            (tmp_path / "words.acl").write_text(f"{OPEN}topic deny {WORDS}\n")
            start = broker.log.stat().st_size
            broker.restart()
            denied = f"Denied PUBLISH from {app.express.client_id}"
            wait_until(
                lambda: denied in broker.log.read_bytes()[start:].decode(errors="replace"),
                15,
                "the express back and subscribed, its word dropped",
            )
            gate.hold(True)  # the express reads what the broker sends it late
            assert probe.publish("rotor/lock", "ON")  # 1: locked for work on the tower
            gate.refused -= bridge_ids
            wait_until(
                lambda: all(
                    c.subscribed_since is not None for c in (app.client, app.lane, app.lock_lane)
                ),
                15,
                "the bridge's connections back and subscribed",
            )
            mark = probe.mark()
            _stale_lock_off(broker.port)  # 2: an old OFF a link held up, refused by the bridge

            def errors() -> list[str]:
                said = [m.text for m in probe.messages[mark:] if m.topic == "rotor/error"]
                return [t for t in said if "expiry" in t]

            wait_until(errors, 10, "the stale lock OFF refused")
            gate.hold(False)  # the express reads the lock ON now (early)
            wait_until(
                lambda: any("lock ON read" in r.getMessage() for r in caplog.records),
                10,
                "the express's lock ON said to the bridge",
            )
            mark = probe.mark()
            assert probe.publish("rotor/target", "100")  # 3: a turn while locked

            def refused() -> list[str]:
                return [m.text for m in probe.messages[mark:] if m.topic == "rotor/error"]

            def moving() -> bool:
                return emu.wait_for(lambda s: True).is_moving

            wait_until(lambda: refused() or moving(), 10, "the target refused or carried out")
            assert not moving(), f"the rotor turns though locked: {refused()}"
            assert refused(), "the target while locked not refused"
    finally:
        probe.close()
        gate.close()
