"""Review 85: stale.py rule 4 deletes a removed rotator's retained topics (bearing, state, lock,
presets, version, ...) when a group is given its id and root, told by the rotator's ``R/info``
read there (a review: a ghost rotator stayed for ever). Claim rule 5 now has the group publish
``G/info`` on that same topic, and makes it one of the bridge's own topics (topics.py
``owned``): a station whose group ``stack`` was made a rotator ``stack`` for a while and then
a group again keeps the rotator's ``rotor/stack/bearing``, ``state``, ``lock/state``,
``version``, ``presets``, ``control``, ``health`` retained for ever beside the group's topics
(before claim rule 5's G/info, the same steps left the group's two topics alone): a dashboard
on ``rotor/stack/bearing`` shows the old rotator's last bearing as the group's."""

from __future__ import annotations

from pathlib import Path

from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import retained_snapshot
from tests.support.rig import Rig

GROUP = {"groups": [{"id": "stack", "name": "Stack", "rotators": ["upper", "lower"]}]}


def test_a_rotator_made_a_group_again_leaves_no_ghost(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a:
        a.add("upper", emu={"start_az_deg": 0, "jitter_deg": 0})
        a.add("lower", emu={"start_az_deg": 0, "jitter_deg": 0})
        a.add("stack", emu={"start_az_deg": 30, "jitter_deg": 0})
        every = list(a.rotators)
        a.rotators[:] = every[:2]  # a group stack of upper and lower
        a.sections = GROUP
        a.start()
        a.ready("upper")
        a.ready("lower")
        a.stop()
        a.rotators[:] = every  # the group taken out, a rotator stack in its place
        a.sections = {}
        t = probe.caught_up()
        a.start()
        a.ready("stack", after=t)
        assert "rotor/stack/bearing" in retained_snapshot(broker.port, "rotor/stack/#")
        a.stop()
        a.rotators[:] = every[:2]  # and the group stack again
        a.sections = GROUP
        t = probe.caught_up()
        a.start()
        a.ready("upper", after=t)
        a.ready("lower", after=t)
        probe.wait_for("rotor/stack/info", lambda m: b'"group":"stack"' in m.payload, after=t)
        held = retained_snapshot(broker.port, "rotor/stack/#")
        assert sorted(held) == [
            "rotor/stack/availability",
            "rotor/stack/info",
            "rotor/stack/status",
        ], held
