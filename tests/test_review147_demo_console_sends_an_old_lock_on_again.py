"""Review 147, finding 3: since 9b73f8b9 the demo's console keeps every typed command by paho's
message id (bridge/demo/console.py rule 6, ``_typed``), to tell its own messages from typed ones
when it takes paho's unacknowledged queue on a reconnect (``_again``). It forgets them only on a
reconnect, the acknowledged ones too. Message ids wrap at 65535: on a connection that carried
that many messages, one of the console's own (a sync marker, the clean-up) takes the id of a
command typed long before and acknowledged, and if the connection is lost before the broker
acknowledges it, ``_again`` takes it for that old command: a lock ON typed and long since
followed by a lock OFF is sent again and locks the rotator (a STOP alike stops a turn typed
after it), and the console's own message is never sent again. Its parent 1998b9a5 kept nothing
by id.

Real mosquitto (MQTT 5); the console's connection through review 139's relay, dead and then
closed. The 65,535 messages of a long session are stood in for by paho's message id counter,
set to just before the old lock ON's id.

Fixed: console.py rule 6."""

from __future__ import annotations

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath


def test_a_lock_on_long_since_unlocked_is_not_sent_again_when_its_message_id_comes_round(
    broker: Mosquitto,
) -> None:
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    lock = topics.rotator("rotorez").lock
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        assert console.sync(slow(20)), "the console never connected through the relay"
        last_mid = console._client._last_mid
        assert console.command("lock on")  # the user locks the rotator ...
        assert console.command("lock off")  # ... and later unlocks it
        assert console.sync(slow(20)), "the broker did not take them"  # (acknowledged first)
        watcher.wait_for(lock, "OFF")
        # a long session: 65,535 messages later the ids come round to the lock ON's
        console._client._last_mid = last_mid
        tries = len(relay.levels)
        relay.dead = True  # the path carries nothing; nobody has noticed yet
        assert not console.sync(0.2), "a sync marker went through a dead path"
        relay.cut()  # the dead connection found out at last: closed
        relay.dead = False
        wait_until(lambda: len(relay.levels) > tries, 20, "the console trying to reconnect")
        relay.restore()
        assert console.sync(slow(20)), "the console never came back"
        console.publish(f"{BASE}/console/mark", "after")
        got = watcher.wait_for(f"{BASE}/console/mark", "after")
    finally:
        console.close()
        watcher.close()
        relay.close()
    words = [payload for topic, payload in got if topic == lock]
    assert words == ["ON", "OFF"], (
        f"the lock ON typed before the OFF reached the broker again: {words}"
    )
