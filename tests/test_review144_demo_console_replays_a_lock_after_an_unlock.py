"""Review 144, finding 2: since e7d107fa the demo's console sends a typed ``lock on`` at QoS 1,
kept by paho for the next connection, and ``lock off`` at QoS 0, now or never. When the broker's
PUBACK for the lock ON is lost (the path back from the broker dead, as finding 1), the ON and the
OFF typed after it both reach the bridge, which ends unlocked; on the reconnect paho sends the
unacknowledged ON again, alone, and the rotator is locked once more though the user's last word
was ``lock off``: every target from then on is refused ("rotator is locked"), and the console
says nothing of it (it does not show ``R/lock/state``). Neither parent does this: e7d107fa^ sent
both at QoS 0, 16dff1c0 both at QoS 1, sent again in their order (OFF last).

Real mosquitto (MQTT 5); the console's connection through finding 1's relay; what reaches the
broker read by an MQTT 3.1.1 client there, as the bridge would get it."""

from __future__ import annotations

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review144_demo_console_replays_a_stop_after_a_turn import DeadWayBack


def test_a_lock_on_typed_before_a_lock_off_is_not_sent_again_after_it_on_reconnect(
    broker: Mosquitto,
) -> None:
    relay = DeadWayBack(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    lock = topics.rotator("rotorez").lock
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        assert console.sync(slow(20)), "the console never connected through the relay"
        tries = len(relay.levels)
        relay.back_dead = True  # the broker's answers go nowhere; nobody has noticed yet
        assert console.command("lock on")
        watcher.wait_for(lock, "ON")
        assert console.command("lock off")  # the work on the tower is done
        watcher.wait_for(lock, "OFF")
        relay.cut()  # the dead connection found out at last: closed
        relay.back_dead = False
        wait_until(lambda: len(relay.levels) > tries, 20, "the console trying to reconnect")
        relay.restore()
        assert console.sync(slow(20)), "the console never came back"
        console.publish(f"{BASE}/console/mark", "after")
        got = watcher.wait_for(f"{BASE}/console/mark", "after")
        locks = [m for m in got if m[0] == lock]
        assert locks[-1] == (lock, "OFF"), (
            f"the lock OFF typed last is undone by the lock ON sent again: {locks}"
        )
    finally:
        console.close()
        watcher.close()
        relay.close()
