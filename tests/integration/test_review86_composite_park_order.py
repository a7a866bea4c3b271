"""Review 86 (session/session.py ``Order``, runtime/worker.py ``place``, runtime/composite.py):
e95fa575 gave the bridge's own turns (auto-park, the storm's park) a place in the order of
commands, taken from the rotator's mailbox (``mailbox.ticket``), so that R/status's
``order.turn`` of an auto-park is after every command asked before it (docs/mqtt.md). A
rotator of two boxes runs each box's session in a Worker built on the box's OWN mailbox (the
one only sky answers wake), so its auto-park takes its place from that mailbox's counter,
which no command ever advances: the park's ``turn`` is 1 however many commands came before
it, and R/status says the park comes before them. A remote's old held STOP (remote.py rule 10)
then reads the park as the turn it was asked against, still standing, and goes again when
the station's bridge connects: the auto-park is stopped short of the park (review 83's case,
fixed for one box only). The storm's park takes its place the same way: stopped short,
it leaves the antenna up in the wind.
Real parts: mosquitto, the bridge, an RT-21 (azimuth) and a GS-232B (elevation) on ptys."""

from __future__ import annotations

import json
from typing import Any

import pytest

from tests.integration.test_composite_bridge import composite
from tests.support.mqtt import Message
from tests.support.rig import Rig

PARKS = {  # the bridge's own turns: auto-park after the quiet spell, the storm's park
    "auto-park": {"park_az_deg": 10, "park_el_deg": 0, "park_after_idle_s": 5},
    "storm park": {"wind_topic": "weather/wind", "wind_park_above": 60, "wind_park_az_deg": 180},
}


def doc(m: Message) -> dict[str, Any]:
    said: dict[str, Any] = json.loads(m.payload)
    return said


def turning(said: dict[str, Any]) -> bool:
    return said.get("target") is not None or said.get("target_elevation") is not None


@pytest.mark.parametrize("park", list(PARKS))
def test_a_composite_parks_turn_is_placed_after_the_commands_before_it(rig: Rig, park: str) -> None:
    composite(rig)
    rig.rotators[-1].update(PARKS[park])
    rig.start()
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)
    rig.probe.publish("rotor/target", "100 20")
    rig.probe.wait_for("rotor/status", lambda m: (doc(m).get("bearing") or 0) > 40, 15)
    for _ in range(3):  # stops: each takes the next place (docs/mqtt.md's ``order``)
        rig.probe.publish("rotor/stop", "stop")
    at_rest = rig.probe.wait_for(
        "rotor/status",
        lambda m: doc(m)["order"]["taken"] >= 4 and doc(m)["state"] == "idle",
        15,
    )
    before = doc(at_rest)["order"]["taken"]
    if park == "storm park":
        rig.probe.publish("weather/wind", "90")  # a storm: the bridge parks the antenna
    parking = rig.probe.wait_for(  # the bridge's own turn: the quiet spell's park, the storm's
        "rotor/status", lambda m: m.t > at_rest.t and turning(doc(m)), 30
    )
    order = doc(parking)["order"]
    assert order["turn"] > before, (
        f"the {park}, begun after commands up to place {before}, shows order.turn "
        f"{order['turn']}, target {doc(parking)['target']} (docs/mqtt.md: a place of its own "
        "after every command asked before it)"
    )


@pytest.mark.parametrize("park", list(PARKS))
def test_a_composite_parks_its_two_boxes_at_one_place_in_the_order(rig: Rig, park: str) -> None:
    """Both boxes park their axes as one turn of the rotator's (runtime/composite.py rule 10):
    every status of the park names one place, the next after the commands before it, and no
    status goes back in the order (each box drawing a place of its own, the park showed one
    box's place, then the other's)."""
    composite(rig)
    rig.rotators[-1].update(PARKS[park])
    rig.start()
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)
    rig.probe.publish("rotor/target", "100 20")
    at_rest = rig.probe.wait_for(  # at the target: nothing more asked
        "rotor/status",
        lambda m: (doc(m).get("bearing") or 0) > 99 and doc(m)["state"] == "idle",
        30,
    )
    before = doc(at_rest)["order"]["taken"]
    if park == "storm park":
        rig.probe.publish("weather/wind", "90")
    rig.probe.wait_for("rotor/status", lambda m: m.t > at_rest.t and turning(doc(m)), 30)
    rig.probe.wait_for(
        "rotor/status",
        lambda m: m.t > at_rest.t and not turning(doc(m)) and doc(m)["state"] == "idle",
        60,
    )
    orders = [doc(m)["order"] for m in rig.probe.on("rotor/status") if m.t > at_rest.t]
    turns = {o["turn"] for o in orders if o["turn"] > before}
    assert turns == {before + 1}, f"the {park}'s statuses named places {sorted(turns)}"
    taken = [o["taken"] for o in orders]
    assert taken == sorted(taken), f"the order went back during the {park}: {taken}"
