"""Review 91 (runtime/composite.py rule 10, 761129f9): "both boxes' parks of one turn take one
place in the order" holds only for parks begun in one serve of the composite worker. A storm
that begins while the elevation box is unplugged parks the azimuth at once (one place); when
the elevation box is plugged back, still in the same storm, its half of the same park begins
in a later serve and draws a second ticket from the rotator's mailbox: R/status's
``order.turn`` names the storm's one park at two places, the review-86 shape (a remote's STOP
asked against the park reads the second place as a newer turn and lets go of its hold:
interfaces/mqtt/remote.py rule 10). No command was asked between the two.
Real parts: mosquitto, the bridge, an RT-21 (azimuth) and a GS-232B (elevation) on ptys."""

from __future__ import annotations

import json
from typing import Any

from tests.integration.test_composite_bridge import composite
from tests.support.mqtt import Message
from tests.support.rig import Rig
from tests.support.waiting import slow

STORM = {
    "wind_topic": "weather/wind",
    "wind_park_above": 60,
    "wind_park_az_deg": 180,
    "park_az_deg": 10,
    "park_el_deg": 0,
}


def doc(m: Message) -> dict[str, Any]:
    said: dict[str, Any] = json.loads(m.payload)
    return said


def test_a_storm_park_finished_after_a_box_replug_keeps_one_place(rig: Rig) -> None:
    _, el = composite(rig)
    rig.rotators[-1].update(STORM)
    rig.start()
    rig.probe.wait_value("rotor/availability", "online", timeout_s=slow(15))
    rig.probe.wait_value("rotor/state", "idle", timeout_s=slow(15))
    rig.probe.publish("rotor/target", "100 20")
    at_rest = rig.probe.wait_for(
        "rotor/status",
        lambda m: (
            (doc(m).get("bearing") or 0) > 99
            and (doc(m).get("elevation") or 0) > 19
            and doc(m)["state"] == "idle"
        ),
        slow(30),
    )
    before = doc(at_rest)["order"]["taken"]
    el.unplug()  # the elevation box's USB out: the storm begins without it
    rig.probe.wait_for(
        "rotor/status", lambda m: m.t > at_rest.t and not doc(m)["available"], slow(15)
    )
    rig.probe.publish("weather/wind", "90")
    rig.probe.wait_for(  # the azimuth box parks at once
        "rotor/status",
        lambda m: m.t > at_rest.t and (doc(m).get("bearing") or 0) > 170,
        slow(30),
    )
    el.replug()  # back, mid-storm: its half of the park follows
    rig.probe.wait_for(
        "rotor/status",
        lambda m: (
            m.t > at_rest.t
            and doc(m)["available"]
            and doc(m).get("elevation") is not None
            and doc(m)["elevation"] < 1
            and doc(m)["state"] == "idle"
        ),
        slow(60),
    )
    orders = [doc(m)["order"] for m in rig.probe.on("rotor/status") if m.t > at_rest.t]
    turns = sorted({o["turn"] for o in orders if o["turn"] > before})
    assert turns == [before + 1], f"the storm's one park named places {turns}"
