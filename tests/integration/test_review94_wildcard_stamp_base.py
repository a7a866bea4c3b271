"""Review 94: claim.py rule 5's vouch reads (``vouch_reads``) are the bridge info and state on
the base topic a stamp seen on a post names, subscribed once the first hello is back
(client.py ``_reads_only``) and unsubscribed when the look ends (``_open``). The base topic is
whatever the stamp says: one retained message on ``rotor/info`` (a post of a bridge on
``rotor`` with two rotators, none of its own topics: nothing it publishes puts it right)
stamped with ``"base_topic": "#"`` makes the vouch read ``#/bridge/info``, which paho refuses
to subscribe (ValueError on paho's thread: the second hello never goes out), so the look
times out after 5 s ("does the broker's ACL deny rotor/bridge/hello?"), and the unsubscribe
of that filter at the open is a malformed packet the broker drops the connection for, before
``online`` goes out. Every reconnect does the same: the bridge never comes online and no
target is ever carried out, for as long as the forged message stays. So does any base topic
that is no topic: a lone surrogate (``"\\ud800"`` in the JSON: UnicodeEncodeError in paho), a
NUL (the broker drops the connection, and the bridge then blames a second client with its
client id); and one past MQTT's length. A stamp whose base topic is ``rotor/gone`` lets the same
bridge run at once. Fixed: a stamp whose base topic no bridge could have (the configuration's own
rule for a base topic) is no stamp, said once in the log, and nothing is read for it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.support import Probe, slow
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


@pytest.mark.parametrize(
    "base",
    ["#", "\ud800", "a\u0000b", "x" * 70000],
    ids=["hash", "surrogate", "nul", "past-mqtt-length"],
)
def test_a_stamp_naming_a_base_topic_that_is_no_topic_does_not_keep_the_bridge_off_the_broker(
    tmp_path: Path,
    broker: Mosquitto,
    probe: Probe,
    base: str,
    caplog: pytest.LogCaptureFixture,
) -> None:
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
    said = [r.getMessage() for r in caplog.records if "no bridge's stamp" in r.getMessage()]
    assert len(said) == 1 and said[0].startswith("rotor/info names a bridge on base topic"), said
