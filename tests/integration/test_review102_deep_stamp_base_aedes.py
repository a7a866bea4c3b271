"""Review 102: a stamp's base topic that passes the configuration's rule for ``mqtt.base_topic``
(settings/mqtt.py ``check_topic``, since review 94) is read: the look subscribes
``<base>/bridge/info`` and ``<base>/bridge/state`` (claim.py rule 5's vouch reads). aedes 0.46,
the broker Node-RED's node-red-contrib-aedes embeds (docs/brokers.md: tested), matches filters
with qlobber, which throws on a filter of more than 100 levels: the exception is not caught,
and the broker process dies (every client of it, Node-RED's flows too when embedded). One
retained message on ``rotor/info`` (a post of a bridge on ``rotor`` with two rotators) stamped
with a base topic of 99 levels ``a/a/.../a`` (197 bytes) has a bridge started on ``rotor``
kill the broker with its vouch read, at its first look; a broker restarted with its retained
messages (persistence) is killed again at the bridge's next connect. With 90 levels the same
bridge runs."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import Probe, slow
from tests.support.brokers import Aedes, find_aedes
from tests.support.rig import Rig

LEVELS = 99  # with "/bridge/info": 101, past qlobber's 100


@pytest.fixture
def aedes(tmp_path: Path) -> Iterator[tuple[Aedes, Probe]]:
    if find_aedes() is None:
        pytest.fail("aedes is not installed (tests/run installs it: npm ci in tests/brokers/aedes)")
    broker = Aedes(tmp_path / "aedes")
    broker.start()
    probe = Probe(broker.port)
    try:
        yield broker, probe
    finally:
        probe.close()
        broker.stop()


def test_on_aedes_a_stamp_naming_a_deep_base_topic_does_not_kill_the_broker(
    tmp_path: Path, aedes: tuple[Aedes, Probe]
) -> None:
    broker, probe = aedes
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
        assert broker.proc is not None and broker.proc.poll() is None, "the broker died"
