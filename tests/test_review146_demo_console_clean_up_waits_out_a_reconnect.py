"""Review 146, finding 4: since 9b73f8b9 the demo's console takes paho's unacknowledged messages
on each reconnect (bridge/demo/console.py rule 6, ``drop_out_messages``) and publishes its own
ones again as new messages. The end-of-run clean-up (``remove_retained``, run as the demo quits)
waits on the messages it first published (``wait_for_publish``): those it no longer has are
never marked sent, and it waits each one's whole timeout, one after the other, though the broker
took them all again at once on the new connection. A demo whose console's connection went and
came back under its clean-up hangs at ``q`` for 3 s a retained message (the demo's bridge leaves
dozens: its state, its Home Assistant configs); the private-broker mark (``mark_private_broker``,
5 s) alike. Its parent 1998b9a5 let paho send the same messages again, and the wait ended as
soon as they were acknowledged.

Real mosquitto (MQTT 5); the console's connection through review 144's relay whose way back
dies right after the clean-up's sync, then closed and restored; a long timeout for each wait, so
that the clean-up ends when the broker has taken it, or hangs.

Fixed: console.py rule 6."""

from __future__ import annotations

import threading

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review144_demo_console_replays_a_stop_after_a_turn import DeadWayBack


def test_the_clean_up_ends_once_the_broker_has_taken_it_again_after_a_reconnect(
    broker: Mosquitto,
) -> None:
    relay = DeadWayBack(broker.port)
    watcher = Watcher(broker.port)
    kept = [f"{BASE}/kept/{i}" for i in range(2)]
    for topic in kept:  # left retained by the demo's bridge
        watcher._client.publish(topic, b"x", qos=1, retain=True).wait_for_publish(slow(20))
    topics = Topics(BASE, {"rotorez": BASE})
    console = console_through(relay.port, topics, mqtt5=True)
    wait_s = slow(20)
    sync = console.sync

    def sync_then_dead_way_back(timeout_s: float = 5.0) -> bool:
        ok = sync(timeout_s)
        relay.back_dead = True  # the broker's PUBACKs for the clean-up go nowhere
        return ok

    ended: list[int | None] = []
    try:
        assert console.sync(slow(20)), "the console never connected through the relay"
        wait_until(lambda: all(console.retained(t) for t in kept), 20, "the retained seen")
        tries = len(relay.levels)
        console.sync = sync_then_dead_way_back  # type: ignore[method-assign]
        cleaning = threading.Thread(
            target=lambda: ended.append(console.remove_retained(timeout_s=3 * wait_s)),
            daemon=True,
        )
        cleaning.start()
        watcher.wait_for(kept[-1], "")  # the clean-up reached the broker; its answers did not
        relay.cut()  # the dead connection found out at last: closed
        relay.back_dead = False
        wait_until(lambda: len(relay.levels) > tries, 20, "the console trying to reconnect")
        relay.restore()
        wait_until(console.connected.is_set, 20, "the console back")
        cleaning.join(wait_s)
        assert ended == [len(kept)], (
            "the clean-up still waits for messages the broker took again on the reconnect"
        )
    finally:
        console.close()
        watcher.close()
        relay.close()
