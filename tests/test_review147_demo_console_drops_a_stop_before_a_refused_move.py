"""Review 147, finding 4: since 9b73f8b9 the demo's console (bridge/demo/console.py rule 6)
sends again, as the next connection comes up, a rotator's typed commands the broker did not
acknowledge that come after its last one "that can move it" (``_kind``); 8dbbaad5 made a
refused ``lock`` word (review 146 (2): ``lock of``) no move, but a move the bridge refuses as
surely is still one: a preset name the rotator does not have (the console knows its presets:
``R/presets``, listed by ``help``), a target that is no JSON (``{nope``). A STOP typed before
such a typo on a connection gone dead is said "not sure it was sent ... type it again" and not
sent again, and the rotor runs on to its target, though sending it again could move nothing
and nothing that moves was typed behind it. Its parent 1998b9a5 sent both again in their order
(the bridge refusing the typo), and the rotor stopped.

Real mosquitto (MQTT 5, the demo's usual broker); the rotator's presets retained on it as the
bridge publishes them; the console's connection through review 139's relay, dead and then
closed; what reaches the broker read by an MQTT 3.1.1 client there.

Fixed: console.py rule 6."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path


@pytest.mark.parametrize("behind", ["preset NOSUCH", "{nope"])
def test_a_stop_typed_before_a_refused_move_goes_again_on_reconnect(
    broker: Mosquitto, behind: str
) -> None:
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    r = topics.rotator("rotorez")
    watcher._client.publish(r.presets, b'{"JA":45,"W":300}', qos=1, retain=True).wait_for_publish(
        slow(20)
    )
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        assert console.sync(slow(20)), "the console never connected through the relay"
        wait_until(lambda: "JA, W" in console.help_text(), 20, "the presets listed by help")
        got = typed_on_a_dead_path(console, relay, watcher, ["s", behind], "STOP")
    finally:
        console.close()
        watcher.close()
        relay.close()
    assert (r.stop, "STOP") in got, (
        f"the STOP typed before {behind!r} never reached the broker: {got}"
    )
