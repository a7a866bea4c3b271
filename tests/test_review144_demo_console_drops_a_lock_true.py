"""Review 144, finding 3: e7d107fa sends a typed lock ON at QoS 1, kept by paho for the next
connection (bridge/demo/console.py rule 3b, review 139 (3)), but tells a lock ON by the word
``ON`` alone. The bridge takes ``1`` and ``true`` as ON too (payloads.py ``parse_switch``; the
halts that carry a lock ON fast do as well), so ``lock true`` or ``lock 1`` typed on a dead
connection still goes at QoS 0 into a socket that carries nothing: the rotator stays unlocked
after the reconnect, and the console says nothing. Its grandparent 16dff1c0 sent every lock at
QoS 1 and paho sent it again on the next connection (e7d107fa^ lost it too, as any lock ON).

Real mosquitto (MQTT 5); review 139's dead path; what reaches the broker read by an MQTT 3.1.1
client there."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path


@pytest.mark.parametrize("word", ["true", "1"])
def test_a_lock_on_spelt_true_or_1_on_a_dead_connection_reaches_the_broker_on_reconnect(
    broker: Mosquitto, word: str
) -> None:
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    lock = topics.rotator("rotorez").lock
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        got = typed_on_a_dead_path(console, relay, watcher, f"lock {word}", "lock")
        locks = [m for m in got if m[0] == lock]
        assert locks == [(lock, word.upper())], (
            f"the lock {word} typed on the dead connection never reached the broker: {got}"
        )
    finally:
        console.close()
        watcher.close()
        relay.close()
