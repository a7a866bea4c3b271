"""R/status's ``order`` (docs/mqtt.md; core/model.py Order): where the status stands in the
order of the commands the bridge took for the rotator, which a remote orders its held halts
by (interfaces/mqtt/remote.py rule 10). Real parts: mosquitto, the bridge on an emulated
Rotor-EZ, each command published as a front end would."""

from __future__ import annotations

import json
from typing import Any

from tests.support import wait_until
from tests.support.mqtt import Message
from tests.support.rig import Rig
from tests.support.waiting import slow


def _order_after(rig: Rig, leaf: str, payload: str, shown: str) -> dict[str, Any]:
    """The ``order`` of the first status after ``payload`` on ``R/leaf`` that says ``shown``."""
    status = rig.topic("tower", "status")
    mark = rig.probe.mark()
    rig.probe.publish(rig.topic("tower", leaf), payload)

    def says(m: Message) -> bool:
        return m.topic == status and shown in m.payload.decode()

    said = rig.probe.wait(says, slow(10), f"the status after {leaf} {payload}", mark)
    order: dict[str, Any] = json.loads(said.payload)["order"]
    return order


def test_each_command_takes_a_later_place_and_the_status_names_its_turns_and_locks(
    rig: Rig,
) -> None:
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0, "speed_deg_s": 20.0})
    rig.start()
    rig.ready("tower")
    first = _order_after(rig, "target", "200", '"target":200.0')
    assert first["turn"] == first["taken"] > 0  # the turn shown is the newest command's
    stopped = _order_after(rig, "stop", "stop", '"target":null')
    assert stopped["run"] == first["run"] and stopped["taken"] > first["taken"]
    locked = _order_after(rig, "lock", "ON", '"locked":true')
    assert locked["lock"] == locked["taken"] > stopped["taken"]
    again = _order_after(rig, "lock", "OFF", '"locked":false')
    assert again["lock"] > locked["lock"]
    turn = _order_after(rig, "target", "100", '"target":100.0')
    assert turn["turn"] == turn["taken"] > again["lock"] > first["turn"]


def test_the_places_go_on_across_a_restart_and_the_new_run_shows_the_turn_and_lock_kept(
    rig: Rig,
) -> None:
    """Review 86 (runtime/kept.py rule 12): after a restart the status counts on after every
    place of the run before (``since``), and shows the turn and the lock word the state file
    kept at their own places, so a remote orders a halt it held over the restart against them
    (tests/remote/test_review86_*: with places from 1 again, a lock OFF or a turn taken before
    the restart looked older than that halt, and was undone)."""
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0, "speed_deg_s": 5.0})
    rig.start()
    rig.ready("tower")
    _order_after(rig, "lock", "ON", '"locked":true')
    off = _order_after(rig, "lock", "OFF", '"locked":false')
    turn = _order_after(rig, "target", "200", '"target":200.0')
    state_file = rig.tmp / "state.json"

    def kept() -> dict[str, Any]:
        entry: dict[str, Any] = json.loads(state_file.read_text())["rotators"]["tower"]
        return entry.get("order", {})

    wait_until(  # the rotor turning: a reading of it saves the places (rule 12)
        lambda: (kept().get("turn"), kept().get("lock")) == (turn["turn"], off["lock"]),
        slow(10),
        "the state file keeping the turn's and the lock word's places",
    )
    rig.stop()
    status = rig.topic("tower", "status")
    mark = rig.probe.mark()
    rig.start()
    new = rig.probe.wait(
        lambda m: m.topic == status and json.loads(m.payload)["order"]["run"] != turn["run"],
        slow(10),
        "the new run's status",
        mark,
    )
    order = json.loads(new.payload)["order"]
    assert order["since"] >= turn["taken"]  # no place of the run before is past it
    assert (order["turn"], order["lock"]) == (turn["turn"], off["lock"])
    rig.probe.wait(  # (the box stopped by the new run: its unasked move, as configured)
        lambda m: m.topic == status and json.loads(m.payload)["state"] == "idle",
        slow(30),
        "the new run's rotor at rest",
        mark,
    )
    again = _order_after(rig, "target", "100", '"target":100.0')
    assert again["turn"] > order["since"]  # a command of the new run comes after them all
