"""Review 149, finding 1: since cd999448 the demo's console (bridge/demo/console.py rule 6)
counts a typed target "neither numbers nor a JSON object" as no move (``_may_move``), and so
sends it again, as the next connection comes up, when the broker never acknowledged it. But the
bridge reads a target's two fields parted by a comma or a semicolon too (payloads ``_SPLIT``):
``120 , 30`` and ``120 ;30`` are the bearing 120, elevation 30 to it. Typed on a connection gone
dead, such a target is sent again when the console reconnects, seconds later, and the rotor turns
then, unasked: rule 6's "a move sent late would turn the rotor seconds after it was typed"
(review 134). Its parent 8dbbaad5 counted every target as a move: said "not sure it was sent",
never sent again.

Real mosquitto (MQTT 5, the demo's usual broker); the console's connection through review 139's
relay, dead and then closed; what reaches the broker read by an MQTT 3.1.1 client there.

Fixed: console.py rule 6 (``_may_move`` reads with the bridge's own parsers)."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.payloads import parse_aim
from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path


@pytest.mark.parametrize("typed", ["120 , 30", "120 ;30"])
def test_a_target_typed_with_a_comma_on_a_dead_connection_is_not_sent_late(
    broker: Mosquitto, typed: str
) -> None:
    assert parse_aim(typed.encode()) == (120.0, 30.0)  # the bridge turns the rotor on it
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    r = topics.rotator("rotorez")
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        assert console.sync(slow(20)), "the console never connected through the relay"
        got = typed_on_a_dead_path(console, relay, watcher, typed, "target")
    finally:
        console.close()
        watcher.close()
        relay.close()
    assert (r.target, typed) not in got, (
        f"the target {typed!r} typed on the dead connection reached the broker late: {got}"
    )
