"""Review 94: claim.py rule 5's vouch reads (the bridge info and state on the base topic a
not-online, unstopped stamp on a post names) are subscribed once the first hello is back, and
a second hello sent right after ends the look: "their retained values come before it" (look.py
rule 14), and one another filter reads came before the first (review 90). Which to read is
decided when the first hello is back (``probes``), by the stamps seen by then. aedes 0.46, the
broker Node-RED's node-red-contrib-aedes embeds (docs/brokers.md: tested), hands a
subscription's retained messages beside what is published after it, not before: the stamp on
``rotor/tower/info`` (read by the bridge's own filter) comes after the first hello, no vouch
read is subscribed (``reads`` was empty in every run), the stamp is there when the look ends,
and nothing vouches for it. So a live bridge on ``shack`` whose tower
(``topic = "rotor/tower"``) has its controller off
is taken for gone ("gone, left rotor/tower/info on this bridge's topics: taken over") by a
bridge started on ``rotor`` with a rotator ``tower``, which runs: it says ``online``, and the
two put their own values back over each other on ``rotor/tower/*`` ("another client
published ... put back"), the tower's info, state, availability and status flipping between
the two bridges' for every subscriber; at a later reconnect's look the second bridge may be
refused, or not. (The one target turning both rotors, rule 5's reason, was not seen here: the
second bridge's tower refused motion "until the broker's R/lock/state is read" in every run,
even after a lock word.) Also so with the live bridge on ``rotor/shack`` (review 90's: its
state read by stale.py's ``rotor/+/bridge/state``). On mosquitto
(tests/integration/test_review85_custom_topic_controller_off.py, test_review90_*) and NATS the
same bridge is refused at its start; on aedes the posts alone (attack 18: the live bridge's own
``R/availability`` ``online``, or the bridge info above) still refuse it. Fixed: the look asks
again (one more hello) while a stamp seen since names a base topic it did not read yet, and
while the broker is still handing over what it held (a retained message after the bridge's
last own message came back), each round's vouch reads subscribed before its hello, which
goes once their SUBACK is in; a vouch read's value came after the hello sent right after
subscribing it, too."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import Probe, wait_until
from tests.support.brokers import Aedes, find_aedes
from tests.support.rig import Rig


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


@pytest.mark.parametrize("other", ["shack", "rotor/shack"])
def test_on_aedes_a_live_bridge_vouches_for_its_rotator_with_its_controller_off(
    tmp_path: Path, aedes: tuple[Aedes, Probe], other: str
) -> None:
    broker, probe = aedes
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.base = other  # bridge A, its tower's topic of its own rotor/tower
        tower = a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0}, topic="rotor/tower")
        a.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        tower.set_silent(True)  # the tower's controller switched off
        first = a.start()
        a.ready("yagi")
        probe.wait_value("rotor/tower/availability", "offline")
        probe.wait_value(f"{other}/bridge/state", "online")
        b.base = "rotor"  # bridge B: its rotator tower's topics are rotor/tower, A's tower's
        b.add("tower", emu={"start_az_deg": 200, "jitter_deg": 0})
        b.add("dish", emu={"start_az_deg": 0, "jitter_deg": 0})  # (two: each on its own root)
        t = probe.caught_up()
        second = b.start()
        wait_until(
            lambda: (
                second.failed.is_set()
                or any(m.t >= t and m.text == "online" for m in probe.on("rotor/bridge/state"))
            ),
            what="the bridge on rotor to be refused, or to say online",
        )
        assert second.failed.is_set(), "the bridge on rotor runs beside the live one"
        assert "rotor/tower/info" in (second.failure or "")
        assert not first.failed.is_set()
