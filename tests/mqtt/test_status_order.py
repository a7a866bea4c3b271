"""R/status's ``order`` (docs/mqtt.md; core/model.py Order): where the status stands in the
order of the commands the bridge took for the rotator, which a remote orders its held halts
by (interfaces/mqtt/remote.py rule 10). Real parts: mosquitto, the bridge on an emulated
Rotor-EZ, each command published as a front end would."""

from __future__ import annotations

import json
from typing import Any

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
