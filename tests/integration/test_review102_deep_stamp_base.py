"""Review 102: since review 94 a stamp's base topic is judged by the configuration's own rule
for ``mqtt.base_topic`` (settings/mqtt.py ``check_topic``: no wildcard, no NUL, no control
character, UTF-8, short enough), and one that passes is read: the look subscribes
``<base>/bridge/info`` and ``<base>/bridge/state`` (claim.py rule 5's vouch reads). The rule has
no word on how many levels a topic has, and brokers do: mosquitto 2.0 drops the connection of a
client that subscribes a filter of more than 200 levels ("Unspecified error"; a filter of 150
levels is granted). One retained message on ``rotor/info`` (a post of a bridge on ``rotor``
with two rotators) stamped with a base topic of 250 levels ``a/a/.../a`` (499 bytes, well
inside MQTT's length) makes the look's vouch read a filter mosquitto drops the bridge for; at
every connect: the bridge never says ``online`` and no target is carried out, for as long as the
forged message stays (review 94's scene with a '#', back with a deep topic)."""

from __future__ import annotations

import json
from pathlib import Path

from tests.support import Probe, slow
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig

LEVELS = 250  # mosquitto 2.0 drops a subscriber past 200 levels


def test_a_stamp_naming_a_base_topic_too_deep_for_the_broker_does_not_keep_the_bridge_off_it(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    base = "/".join(["a"] * LEVELS)
    forged = {"id": "tower", "bridge": {"instance": "ghost", "base_topic": base}}
    assert probe.publish("rotor/info", json.dumps(forged), retain=True)
    with Rig(tmp_path / "b", broker, probe) as b:
        mast = b.add("tower", emu={"start_az_deg": 200, "jitter_deg": 0})
        b.add("dish", emu={"start_az_deg": 0, "jitter_deg": 0})  # (two: rotor/info is no root)
        t = probe.caught_up()
        app = b.start()
        probe.wait_value("rotor/bridge/state", "online", after=t)
        b.ready("tower")
        probe.publish("rotor/tower/target", "90")
        mast.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, slow(15))
        assert not app.failed.is_set(), app.failure
