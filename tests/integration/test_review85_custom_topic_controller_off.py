"""Review 85: claim.py rule 5 vouches for a rotator's stamp (``R/info`` says ``offline``: its
controller switched off) only by the bridge info on a topic above the looking bridge's base
topic (``above``: ``A/bridge/info``), read where the stamp's base topic would be. A rotator
with a ``topic`` of its own lies under no base topic of its bridge: bridge A on ``shack`` with
a rotator ``tower`` at ``topic = "rotor/tower"`` stamps ``{"instance": A, "base_topic":
"shack"}``, and ``shack/bridge/info`` is never read by a bridge on ``rotor/tower``. With the
tower's controller off (a station's everyday state), a bridge started on ``rotor/tower`` takes
live bridge A for gone and runs; once the controller is switched on, one target on
``rotor/tower/target`` turns both rotors (review 77's clash, back through a rotator's own
topic)."""

from __future__ import annotations

from pathlib import Path

from tests.integration.test_review77_controller_off import second_bridge_never_turns_with_the_tower
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def test_a_bridge_on_a_live_bridges_own_rotator_topic_whose_controller_is_off_never_runs(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.base = "shack"  # bridge A: base topic shack, its tower's topic of its own rotor/tower
        tower = a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0}, topic="rotor/tower")
        a.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        tower.set_silent(True)  # the tower's controller switched off
        first = a.start()
        a.ready("yagi")
        probe.wait_value("rotor/tower/availability", "offline")
        b.base = "rotor/tower"  # bridge B's one rotator's topics are A's tower's
        mast = b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        second_bridge_never_turns_with_the_tower(probe, first, b, tower, mast)


def test_a_bridge_whose_own_rotator_topic_is_a_live_bridges_rotator_whose_controller_is_off_never_runs(  # noqa: E501
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """The same defect's other face: the looking bridge's rotator has the topic of its own,
    and ``above`` is read only above its base topic, never above that rotator's topic."""
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        tower = a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})  # rotor/tower
        a.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        tower.set_silent(True)  # the tower's controller switched off
        first = a.start()
        a.ready("yagi")
        probe.wait_value("rotor/tower/availability", "offline")
        b.base = "site"  # bridge B: base topic site, its one rotator's topic A's tower's
        mast = b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0}, topic="rotor/tower")
        second_bridge_never_turns_with_the_tower(probe, first, b, tower, mast)
