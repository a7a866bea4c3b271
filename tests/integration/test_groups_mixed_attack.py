"""Attack pass on groups end to end: a 450-degree Yaesu and a south-centred Rotor-EZ in one
group, the Rotor-EZ locked: a G/target turns the Yaesu alone (no byte of motion to the locked
one), unlocking replays nothing, and a G/target then turns both, each on its own scale."""

from __future__ import annotations

import json
import time

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from tests.support.rig import Rig
from tests.support.waiting import wait_until


def test_a_locked_member_of_mixed_scales_gets_nothing_and_nothing_replays(rig: Rig) -> None:
    up = rig.add("upper", model="gs232b-az-450", emu={"start_az_deg": 250})
    low = rig.add("lower", emu={"start_az_deg": 90}, az_offset_deg=180)  # true 270
    rig.sections = {
        "groups": [
            {
                "id": "stack",
                "rotators": ["upper", "lower"],
                "limits": {"upper": [20, 340], "lower": [200, 360]},
            }
        ]
    }
    rig.start()
    rig.ready("upper")
    rig.ready("lower")
    rig.probe.publish("rotor/lower/lock", "ON")
    rig.probe.wait_value("rotor/lower/lock/state", "ON")
    t = time.monotonic()
    rig.probe.publish("rotor/stack/target", "0")  # upper: outside 20..340; lower: north, locked
    err = rig.probe.wait_for("rotor/stack/error", lambda m: b"members" in m.payload, after=t)
    members = json.loads(err.payload)["members"]
    assert set(members) == {"upper", "lower"} and "locked" in members["lower"]
    rig.probe.publish("rotor/stack/target", "300")
    rig.arrived("upper", 300)
    assert [f.data for f in up.frames("move")] == [b"M300"]
    assert low.frames(*BEARING_OUTCOMES) == []
    rig.probe.publish("rotor/lower/lock", "OFF")
    rig.probe.wait_value("rotor/lower/lock/state", "OFF")
    time.sleep(2.0)
    assert low.frames(*BEARING_OUTCOMES) == []  # nothing replayed by the unlock
    rig.probe.publish("rotor/stack/target", "0")  # lower to north (raw 180), upper refused
    rig.arrived("lower", 180)  # raw: true north on its south-centred scale
    assert [f.data for f in low.frames(*BEARING_OUTCOMES)] == [b"AP1180\r"]
    wait_until(lambda: rig.status("upper").bearing_deg is not None, 5, "upper reads")
    assert abs(rig.status("upper").bearing_deg - 300) <= 3  # upper stayed
    status = json.loads(rig.retained()["rotor/stack/status"])
    assert "upper" in status["refused"] and "lower" not in status["refused"]
