"""Review 96, on the real bridge: a storm's park the next start sends again (session/wind.py rule
7: the bridge stopped before the park was seen reached) takes a new place in R/status's
``order.turn`` (the new run's first place, past its ``since``), though it is the same storm's
park, kept in the state file with the place it had, and no command was asked between
(mailbox.py rule 10b keeps one turn's place within a run only). A remote's STOP pressed
against the park and held over the station's absence (interfaces/mqtt/remote.py rule 10,
``held_stamp``) reads the new run's turn as a newer one and lets go: the rotor turns on though
the operator stopped it. Real parts: mosquitto, the bridge (stopped and started again on its
state file), a Rotor-EZ on a pty (tests/engine/test_review96_storm_park_restart_place.py is
the same in virtual time)."""

from __future__ import annotations

import json
from typing import Any

from bridge.interfaces.mqtt.remote import held_stamp
from tests.support.mqtt import Message
from tests.support.rig import Rig
from tests.support.waiting import slow

WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "wind_park_az_deg": 180}


def doc(m: Message) -> dict[str, Any]:
    said: dict[str, Any] = json.loads(m.payload)
    return said


def test_a_storm_park_sent_again_by_a_restart_keeps_its_place(rig: Rig) -> None:
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0, "speed_deg_s": 2.0}, **WIND)
    probe = rig.probe
    rig.start()
    rig.ready("tower")
    start = probe.caught_up()
    probe.publish("weather/wind", "90")  # a storm: the park turns 10 -> 180 at 2 deg/s
    parking = probe.wait_for(
        "rotor/status",
        lambda m: doc(m).get("target") is not None and doc(m)["order"]["turn"] > 0,
        slow(15),
        after=start,
    )
    park_place = doc(parking)["order"]["turn"]
    probe.wait_for(  # (a few seconds into the turn: its place saved, kept.py rule 12)
        "rotor/status",
        lambda m: m.t > parking.t + slow(3) and doc(m)["state"] == "moving",
        slow(15),
    )
    before: dict[str, tuple[int, ...]] = {}  # a remote's STOP pressed now: its stamp's ledger
    for m in probe.on("rotor/status"):
        order = doc(m)["order"]
        before[order["run"]] = (*before.get(order["run"], ()), order["taken"])
    rig.stop()
    after = probe.caught_up()
    rig.start()
    again = probe.wait_for(  # the new run's park, sent again
        "rotor/status",
        lambda m: doc(m)["order"]["run"] not in before and doc(m).get("target") is not None,
        slow(20),
        after=after,
    )
    order = doc(again)["order"]
    stamp = held_stamp(before, order["run"], order["taken"], order["since"])
    assert (order["turn"], stamp) == (park_place, park_place), (
        f"the storm's park at place {park_place} before the restart shows {order} after it: "
        f"a STOP stamped {stamp} against it is let go"
    )
