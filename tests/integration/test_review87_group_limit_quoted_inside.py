"""Review 87 (cold review of attack 28's ``shown_past``): a group member's limits refuse a
bearing just past them quoting it as inside them.

Attack 28 found ``R/target 360.00001`` refused as "azimuth 360 outside 0..360", a refusal that
contradicts itself, and quoted such values through core/text.py ``shown_past`` in the judge
and the loggers. A group's own check of a member's ``limits`` (interfaces/mqtt/groups.py,
``fan_out``) still quotes the bearing with ``:g``: a script that sends the stack a computed
great-circle bearing, ``340.0000004``, to a group whose upper yagi keeps out of 340..20
(docs/groups.md's own example, ``limits = { upper = [20, 340] }``) reads on ``G/status`` (Home
Assistant's group attributes) and ``G/error`` that the upper rotor refused "340 is outside
upper's limits in group stack (20..340)". 340 is inside 20..340: the user cannot tell what was
wrong with the target, nor that a rounding would do.

Reproduced on the rig (real mosquitto, emulated controllers on ptys): the lower rotor turns,
the upper one's refusal quotes 340."""

from __future__ import annotations

import json
import re

from tests.support.rig import Rig


def test_a_members_refusal_quotes_a_bearing_past_its_limits_as_past_them(rig: Rig) -> None:
    rig.add("upper", emu={"start_az_deg": 10})
    rig.add("lower", emu={"start_az_deg": 190})
    rig.sections = {
        "groups": [{"id": "stack", "rotators": ["upper", "lower"], "limits": {"upper": [20, 340]}}]
    }
    rig.start()
    rig.ready("upper")
    rig.ready("lower")
    rig.probe.publish("rotor/stack/target", "340.0000004")  # a script's computed bearing
    status = rig.probe.wait_for(
        "rotor/stack/status", lambda m: "upper" in json.loads(m.payload)["refused"]
    )
    said = json.loads(status.payload)["refused"]["upper"]
    assert "lower" not in json.loads(status.payload)["refused"], said
    quoted = re.match(r"[-+0-9.e]+", said)
    assert quoted is not None, said
    assert not 20 <= float(quoted.group()) <= 340, f"the refusal quotes a bearing inside: {said!r}"
