"""Review 139, finding 4: since 725af295 a line typed while the demo's console has lost the broker
is not sent ("now or never", bridge/demo/console.py rule 3b), and ``s`` is no exception: the
console prints "not sent (... STOP)" and the STOP is dropped. The bridge's own connection is
not the console's (a blip on the console's path, a broker that let the bridge back first): the
rotor turns on to its target while the user, having typed ``s``, waits for the console to come
back (1..5 s) to type it again. A STOP moves nothing, so the stale-bearing reason of review 134
(1) does not hold for it; its parent (16dff1c0) kept it (QoS 1) and sent it on the reconnect,
and the rotor stopped then.

Real nats-server (MQTT 3.1.1, where review 134 (1) was found); the console's own connection
through review 134's relay (finding 1's: its cut seen at once), cut and restored; what reaches
the broker is read by an MQTT 3.1.1 client there."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.topics import Topics
from tests.support.brokers import Nats, find_nats
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath


@pytest.fixture
def nats(tmp_path: Path) -> Iterator[Nats]:
    if find_nats() is None:
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    n = Nats(tmp_path / "nats").start()
    yield n
    n.stop()


def test_a_stop_typed_while_the_console_is_cut_off_is_sent_when_it_reconnects(
    nats: Nats,
) -> None:
    relay = DeadPath(nats.port)  # (cut: closed both ways at once)
    watcher = Watcher(nats.port)
    topics = Topics(BASE, {"rotorez": BASE})
    console = console_through(relay.port, topics, mqtt5=False)
    try:
        assert console.sync(slow(20)), "the MQTT 3.1.1 console never connected through the relay"
        tries = len(relay.levels)
        relay.cut()
        wait_until(lambda: len(relay.levels) > tries, 20, "the console trying to reconnect")
        assert console.command("s")  # typed now: the rotor is turning
        relay.restore()
        assert console.sync(slow(20)), "the console never came back"
        console.publish(f"{BASE}/console/mark", "after")
        before = watcher.wait_for(f"{BASE}/console/mark", "after")
        stops = [m for m in before if m[0] == topics.rotator("rotorez").stop]
        assert stops == [(topics.rotator("rotorez").stop, "STOP")], (
            f"the STOP typed while cut off never reached the broker: {before}"
        )
    finally:
        console.close()
        watcher.close()
        relay.close()
