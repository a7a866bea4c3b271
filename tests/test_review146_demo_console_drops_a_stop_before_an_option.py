"""Review 146, finding 2: since 9b73f8b9 the demo's console (bridge/demo/console.py rule 6)
sends again, as the next connection comes up, the typed commands the broker did not acknowledge
"after the last that can move a rotor or lift a lock"; the code cuts after the last command that
is not a STOP or a lock ON, whatever it is. A Rotor-EZ option (``jam off``: a setting of the
controller, it moves nothing), a ``track off``, a mistyped ``lock of`` typed after the STOP on a
dead connection each count as a move: the STOP is said "not sure it was sent ... type it again"
and not sent again, and the rotor runs on to its target, though sending it again could move
nothing and nothing that moves was typed behind it. Its parent 1998b9a5 sent both again, in
their order, and the rotor stopped.

Real mosquitto (MQTT 5, the demo's usual broker); the console's connection through review 139's
relay, dead and then closed; what reaches the broker read by an MQTT 3.1.1 client there.

Fixed: console.py rule 6."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path


@pytest.mark.parametrize("behind", ["jam off", "track off", "lock of"])
def test_a_stop_typed_before_a_command_that_moves_nothing_goes_again_on_reconnect(
    broker: Mosquitto, behind: str
) -> None:
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    stop = topics.rotator("rotorez").stop
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        got = typed_on_a_dead_path(console, relay, watcher, ["s", behind], "STOP")
    finally:
        console.close()
        watcher.close()
        relay.close()
    assert (stop, "STOP") in got, (
        f"the STOP typed before {behind!r} never reached the broker: {got}"
    )
