"""Review 146, finding 3: since 9b73f8b9 the demo's console (bridge/demo/console.py rule 6)
decides what to send again after a lost connection by one cut for all its rotators: every typed
command up to the last move, of any rotator, is said unsure and not sent again. With two
rotators, a STOP typed for the first and a bearing typed for the second behind it (both on a
connection gone dead) leave the first's STOP unsent: it could land after nothing typed for its
own rotor, yet the rotor the user stopped runs on to its target. Its parent 1998b9a5 sent both
again in their order, and the first rotor stopped.

Real mosquitto (MQTT 5, the demo's usual broker); the console's connection through review 139's
relay, dead and then closed; what reaches the broker read by an MQTT 3.1.1 client there.

Fixed: console.py rule 6."""

from __future__ import annotations

from bridge.demo.console import Console
from bridge.demo.screen import Screen
from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path


def test_a_stop_for_one_rotator_goes_again_though_another_was_turned_after_it(
    broker: Mosquitto,
) -> None:
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"one": f"{BASE}/one", "two": f"{BASE}/two"})
    console = Console(
        "127.0.0.1",
        relay.port,
        client_id=f"{BASE}-ui",
        topics=topics,
        rotator_ids=["one", "two"],
        discovery_filters=[],
        screen=Screen(),
        mqtt5=True,
    )
    try:
        got = typed_on_a_dead_path(console, relay, watcher, ["one s", "two 200"], "STOP")
    finally:
        console.close()
        watcher.close()
        relay.close()
    stop = topics.rotator("one").stop
    assert (stop, "STOP") in got, f"the first rotator's STOP never reached the broker: {got}"
