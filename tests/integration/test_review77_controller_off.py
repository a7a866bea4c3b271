"""Review 77: claim.py rule 5 takes a rotator's ``R/info`` with ``R/availability`` other than
``online`` for a gone bridge's. A live bridge's rotator whose controller does not answer says
``offline`` there: its controller switched off between sessions (a station's everyday state),
or not answered yet in the first seconds after a start (both bridges back after a power cut).
A second bridge on that rotator's topic then starts, logging the live bridge as "gone ...
taken over", and once the controller is switched on one target turns both rotors. The rule
says "not seen: a live bridge whose rotator's controller does not answer"; that is not a
rare moment but whenever the controller is off."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bridge.app import App
from bridge.emulators.pty import EmulatedPort
from tests.integration.test_attack18_base_topic_under_a_rotator import (
    station_on_rotor,
    station_on_tower,
)
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def test_a_bridge_on_a_live_bridges_rotator_whose_controller_is_off_never_turns_on_its_targets(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        tower = station_on_rotor(a)
        tower.set_silent(True)  # the tower's controller switched off
        first = a.start()
        a.ready("yagi")
        probe.wait_value("rotor/tower/availability", "offline")
        mast = station_on_tower(b)
        second_bridge_never_turns_with_the_tower(probe, first, b, tower, mast)


def second_bridge_never_turns_with_the_tower(
    probe: Probe, first: App, b: Rig, tower: EmulatedPort[Any], mast: EmulatedPort[Any]
) -> None:
    """Bridge B (its rotator ``mast`` at 200) started while live bridge A's tower on
    ``rotor/tower`` is switched off; the tower switched on and sent to 90: B must have been
    refused, its rotor never turned by A's target."""
    second = b.start()
    if not second.failed.is_set():  # refused at once is the fix; started, its rotator answers
        wait_until(
            lambda: b.status("mast").available or second.failed.is_set(),
            what="the second bridge's rotator to answer",
        )
    t = probe.caught_up()
    tower.set_silent(False)  # switched on: the live bridge's tower answers
    probe.wait_for("rotor/tower/status", lambda m: b'"bearing":0.0' in m.payload, after=t)
    probe.publish("rotor/tower/target", "90")
    tower.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
    after = mast.state()
    assert (after.az_deg, after.is_moving) == (200, False), after
    assert second.failed.is_set() and not first.failed.is_set()
