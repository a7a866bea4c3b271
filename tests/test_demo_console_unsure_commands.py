"""The demo's console, bridge/demo/console.py rule 6: a typed command the broker did not
acknowledge before the connection was lost is not sent again when it is a move (it may have
reached nobody, or the broker: sent late, it would turn the rotor seconds after it was typed),
and the console says so, for the user to type it again.

Real mosquitto (MQTT 5, the demo's usual broker); the console's connection through review 139's
relay, dead and then closed; what reaches the broker read by an MQTT 3.1.1 client there."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path


def test_a_bearing_typed_on_a_dead_connection_is_not_sent_on_the_next_and_is_said_unsure(
    broker: Mosquitto, capsys: pytest.CaptureFixture[str]
) -> None:
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    target = topics.rotator("rotorez").target
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        before = typed_on_a_dead_path(console, relay, watcher, "200", "bearing")
        said = capsys.readouterr().out
    finally:
        console.close()
        watcher.close()
        relay.close()
    assert [m for m in before if m[0] == target] == [], (
        f"a bearing typed on a dead connection reached the broker on the next: {before}"
    )
    assert f"not sure it was sent ({target} 200)" in said, said
