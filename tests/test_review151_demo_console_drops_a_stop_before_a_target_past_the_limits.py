"""Review 151, finding 2: dcfc06de made a typed move count as none (bridge/demo/console.py rule
6, ``_may_move``) only where the bridge's own parser of its topic refuses it. A payload the
parser takes but the bridge still refuses, as the rotator judges it, is still a move to the
console: a bearing past the rotator's travel (``500`` to a Rotor-EZ, 0..360: refused for its
limits) or an elevation to a rotator with none (``el 30`` to a Rotor-EZ). Nothing turns for
either; yet a STOP typed before one on a connection gone dead is said "not sure it was sent" and
not sent again, and the rotor runs on. The rule's words ("a move the bridge's own parser of its
topic refuses ... counts as none") do not cover these; its promise ("nothing that moves it was
typed behind them") does not hold for them. Older: the parent (575ab89a) took both for moves
alike.

Real mosquitto (MQTT 5, the demo's usual broker); the console's connection through review 139's
relay, dead and then closed; what reaches the broker read by an MQTT 3.1.1 client there."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.topics import Topics
from bridge.protocols import REGISTRY
from tests.support.mosquitto import Mosquitto
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path


@pytest.mark.xfail(
    strict=True,
    reason="review-151 2: a STOP typed before a move the rotator refuses ('500' past its "
    "travel, 'el 30' with no elevation) on a dead connection is never sent again; the rotor "
    "runs on",
)
@pytest.mark.parametrize("behind", ["500", "el 30"])
def test_a_stop_typed_before_a_move_the_rotator_refuses_goes_again_on_reconnect(
    broker: Mosquitto, behind: str
) -> None:
    spec = REGISTRY["rotorez"]  # the rotator the console's commands are for: nothing turns
    assert spec.az_max_deg < 500 and not spec.has_elevation
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
