"""Review 149, finding 2: cd999448 (review 147 (4)) made a move the console can tell the bridge
refuses count as none (bridge/demo/console.py rule 6, ``_may_move``), so that a STOP typed before
it on a dead connection is sent again as the next connection comes up. It tells a target by
"all numbers" (Python's ``float``), not by the bridge's own reading (payloads ``parse_aim``):
``+10`` (the nudge buttons' word, which the bridge refuses on the target topic: "a signed step,
a nudge") and ``120 30 5`` (three fields) are still moves to it. A STOP typed before either on a
connection gone dead is said "not sure it was sent" and not sent again, and the rotor runs on to
its target, though sending it again could move nothing and nothing that moves was typed behind
it. Older: 8dbbaad5 and 9b73f8b9 counted every target as a move alike (review 147 (4), left
unfinished for these).

Real mosquitto (MQTT 5, the demo's usual broker); the console's connection through review 139's
relay, dead and then closed; what reaches the broker read by an MQTT 3.1.1 client there.

Fixed: console.py rule 6 (``_may_move`` reads with the bridge's own parsers)."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.payloads import PayloadError, parse_aim
from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path


@pytest.mark.parametrize("behind", ["+10", "120 30 5"])
def test_a_stop_typed_before_a_target_the_bridge_refuses_goes_again_on_reconnect(
    broker: Mosquitto, behind: str
) -> None:
    with pytest.raises(PayloadError):
        parse_aim(behind.encode())  # the bridge refuses it: nothing turns
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    r = topics.rotator("rotorez")
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        got = typed_on_a_dead_path(console, relay, watcher, ["s", behind], "STOP")
    finally:
        console.close()
        watcher.close()
        relay.close()
    assert (r.stop, "STOP") in got, (
        f"the STOP typed before {behind!r} never reached the broker: {got}"
    )
