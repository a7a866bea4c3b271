"""Attack 27 on groups: ``G/status`` keeps "the refusals of the last ``G/target``"
(docs/groups.md, Status), which Home Assistant shows as the attributes of the group's moving
sensor. A target refused whole (a bearing out of range, unreadable, an elevation for an
azimuth-only member, too late) is said on ``G/error`` only: ``G/status`` goes on showing the
refusals of the target before it. Here the lower rotor was locked for the first target (120:
the upper one turned); then the lock came off, and the next target, 400, was refused by the
whole group. The dashboard still says the last target was refused by the lower rotor alone,
because it is locked: neither is true any more, and the upper rotor, which refused it too, is
not named."""

from __future__ import annotations

import json

from tests.support.rig import Rig


def test_a_group_target_refused_whole_replaces_the_refusals_in_its_status(rig: Rig) -> None:
    rig.add("upper", emu={"start_az_deg": 10})
    rig.add("lower", emu={"start_az_deg": 190})
    rig.sections = {"groups": [{"id": "stack", "rotators": ["upper", "lower"]}]}
    rig.start()
    rig.ready("upper")
    rig.ready("lower")
    rig.probe.publish("rotor/lower/lock", "ON")
    rig.probe.wait_value("rotor/lower/lock/state", "ON")
    rig.probe.publish("rotor/stack/target", "120")  # the upper one turns, the lower refuses
    rig.probe.wait_for("rotor/stack/status", lambda m: "lower" in json.loads(m.payload)["refused"])
    rig.arrived("upper", 120)
    rig.probe.publish("rotor/lower/lock", "OFF")
    rig.probe.wait_value("rotor/lower/lock/state", "OFF")
    t = rig.probe.caught_up()
    rig.probe.publish("rotor/stack/target", "400")  # refused by the whole group
    rig.probe.wait_for("rotor/stack/error", lambda m: b"'400'" in m.payload, after=t)
    # a later message on the same connection: whatever the 400 made the bridge publish is out
    rig.probe.publish("rotor/stack/target", "abc")
    rig.probe.wait_for("rotor/stack/error", lambda m: b"'abc'" in m.payload, after=t)
    rig.probe.caught_up()
    refused = json.loads(rig.retained()["rotor/stack/status"])["refused"]
    assert set(refused) == {"upper", "lower"}, (
        f"G/status says the last target's refusals were {refused}: the older target's, the "
        "lower rotor's lock since switched off"
    )
