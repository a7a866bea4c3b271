"""Review 151, finding 3: the console takes a typed preset for no move when the rotator's
retained ``R/presets`` lacks it word for word (bridge/demo/console.py rule 6, ``_may_move``:
``payload in names``), though dcfc06de had it read by the bridge's own parser first
(``parse_name``), and that parser drops what a sender's tools put round the words (a byte-order
mark at the start, NULs at the end: payloads ``_words``). ``preset \\ufeffJA`` (a line pasted
from a Windows tool; ``str.split`` keeps U+FEFF) is the preset ``JA`` to the bridge, which turns
the rotor there; to the console it is a typo, "other", and one typed on a connection gone dead
is sent again, unasked, as the next connection comes up: the rotor turns seconds after it was
typed (rule 6: "a move sent late would turn the rotor seconds after it was typed"). Older: the
parent (575ab89a) compared the raw word with the list alike.

Real mosquitto (MQTT 5, the demo's usual broker); the console's connection through review 139's
relay, dead and then closed; what reaches the broker read by an MQTT 3.1.1 client there.

Fixed: console.py rule 6 (``_kind``, ``_may_move``: what the bridge reads)."""

from __future__ import annotations

import paho.mqtt.publish as publish

from bridge.interfaces.mqtt.payloads import parse_name
from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path

TYPED = "\ufeffJA"


def test_a_preset_typed_with_a_bom_on_a_dead_connection_is_not_sent_late(
    broker: Mosquitto,
) -> None:
    assert parse_name(TYPED.encode(), "preset") == "JA"  # the bridge turns the rotor to JA
    topics = Topics(BASE, {"rotorez": BASE})
    r = topics.rotator("rotorez")
    publish.single(
        r.presets, '{"JA":40}', qos=1, retain=True, hostname="127.0.0.1", port=broker.port
    )
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        assert console.sync(slow(20)), "the console never connected through the relay"
        got = typed_on_a_dead_path(console, relay, watcher, f"preset {TYPED}", "preset")
    finally:
        console.close()
        watcher.close()
        relay.close()
        publish.single(r.presets, b"", qos=1, retain=True, hostname="127.0.0.1", port=broker.port)
    assert (r.preset, TYPED) not in got, (
        f"the preset {TYPED!r} typed on the dead connection reached the broker late: {got}"
    )
