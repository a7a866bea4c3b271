"""Review 151, finding 1: dcfc06de made the console judge a typed move by the bridge's own parser
of its topic (bridge/demo/console.py rule 6, ``_may_move``: "a move the bridge's own parser of
its topic refuses ... counts as none") for the target, elevation, preset, park and nudge topics,
but not for ``R/track``: ``_kind`` still takes every track payload but ``off`` for a move
("tracking begun"). ``track {"tle": []}`` (a TLE with no lines) is refused by the bridge's own
parser of that topic (payloads ``parse_track``, the tracking feature's), so nothing turns; yet a
STOP typed before it on a connection gone dead is said "not sure it was sent" and not sent
again, and the rotor runs on. Older: the parent (575ab89a) took every track but ``off`` for a
move alike.

Real mosquitto (MQTT 5, the demo's usual broker); the console's connection through review 139's
relay, dead and then closed; what reaches the broker read by an MQTT 3.1.1 client there.

Fixed: console.py rule 6 (``_kind``, ``_may_move``: what the bridge reads)."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.payloads import PayloadError, parse_track
from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path

TYPO = '{"tle": []}'


def test_a_stop_typed_before_a_track_the_bridge_refuses_goes_again_on_reconnect(
    broker: Mosquitto,
) -> None:
    with pytest.raises(PayloadError):
        parse_track(TYPO.encode())  # the bridge refuses it: nothing turns
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    r = topics.rotator("rotorez")
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        got = typed_on_a_dead_path(console, relay, watcher, ["s", f"track {TYPO}"], "STOP")
    finally:
        console.close()
        watcher.close()
        relay.close()
    assert (r.stop, "STOP") in got, (
        f"the STOP typed before track {TYPO} never reached the broker: {got}"
    )
