"""Review 139, finding 3: since 725af295 the demo's console sends ``lock on`` at QoS 0 too
(bridge/demo/console.py rule 3b). The safety lock ON is what a user types before climbing the
tower or while someone works on the antenna: on a connection that went dead without paho
knowing yet, it goes into a socket that carries nothing, the console says nothing (it does not
show ``R/lock/state`` either), and after the reconnect the rotator is still unlocked: a target
from Home Assistant or a logger turns it. A lock ON can move nothing, so "never later" (review
134 (1): a stale bearing) is no reason to drop it. Its parent (16dff1c0) sent it at QoS 1,
unacknowledged, and paho sent it again on the next connection.

Real mosquitto (MQTT 5); the console's connection through the relay of finding 1, dead and
then closed; what reaches the broker read by an MQTT 3.1.1 client there."""

from __future__ import annotations

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path


def test_a_lock_on_typed_on_a_dead_connection_reaches_the_broker_once_the_console_reconnects(
    broker: Mosquitto,
) -> None:
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        before = typed_on_a_dead_path(console, relay, watcher, "lock on", "lock")
        locks = [m for m in before if m[0] == topics.rotator("rotorez").lock]
        assert locks == [(topics.rotator("rotorez").lock, "ON")], (
            f"the lock ON typed on the dead connection never reached the broker: {before}"
        )
    finally:
        console.close()
        watcher.close()
        relay.close()
