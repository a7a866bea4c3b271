"""Attack 27 on groups: a rotator's command left retained on a group's topic. A station had a
rotator ``stack`` and made it a group of its two yagis; the old dashboard's ``rotor/stack/lock
ON``, published retained, is still on the broker. At every start the bridge says on
``G/error`` "group stack has no lock: no rotator was locked; send it to each member's own
topic", as if someone had just sent it: nothing says it is a retained message the broker
replays, nor to clear it, where a retained ``G/target`` is said as one ("retained command on
... ignored: ... clear it with an empty retained message"). Nothing moves; the operator
looks for a client sending lock words that does not exist, and the message comes back at
every start until the topic is cleared by someone who knows it is retained."""

from __future__ import annotations

import json

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from tests.support.rig import Rig


def test_a_retained_lock_on_a_groups_topic_is_said_as_retained(rig: Rig) -> None:
    up = rig.add("upper", emu={"start_az_deg": 10})
    low = rig.add("lower", emu={"start_az_deg": 190})
    rig.sections = {"groups": [{"id": "stack", "rotators": ["upper", "lower"]}]}
    rig.probe.publish("rotor/stack/lock", "ON", retain=True)  # left from an old dashboard
    rig.start()
    said = json.loads(
        rig.probe.wait_for("rotor/stack/error", lambda m: b"lock" in m.payload).payload
    )
    rig.ready("upper")
    rig.ready("lower")
    assert said["kind"] == "refused"
    assert up.frames(*BEARING_OUTCOMES) == low.frames(*BEARING_OUTCOMES) == []  # as it must
    assert "retained" in said["message"], said["message"]
