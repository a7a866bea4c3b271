"""Review 77: claim.py rule 5 reads, on a bridge's own topics, where another bridge's rotator
(``R/info``) or bridge (``R/bridge/info``) would say who it is; a group's topics are neither.
A group ``tower`` of a bridge on ``rotor`` has ``rotor/tower/target`` (settings
``group_topic``: ``<base>/<id>``), which a bridge on ``rotor/tower`` with one rotator takes as
its rotator's target too. Nothing of the group names its bridge there (``G/status`` and
``G/availability`` only), so the second bridge starts, in either order, and one target turns
the group's two rotors and the other bridge's rotor: attack 18's clash, through a group.
Fixed for the group's bridge started second (rule 5 reads a group's root as a rotator's: the
other's ``rotor/tower/bridge/info`` and ``online`` refuse it), and the other way round (the
group's ``G/info`` names its bridge, ``G/availability`` beside it)."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.app import App
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def station_with_group(a: Rig) -> None:
    """Bridge A: base topic ``rotor``, rotators ``upper`` and ``lower`` in a group ``tower``
    (its topics ``rotor/tower/...``)."""
    a.add("upper", emu={"start_az_deg": 0, "jitter_deg": 0})
    a.add("lower", emu={"start_az_deg": 0, "jitter_deg": 0})
    a.sections = {"groups": [{"id": "tower", "name": "Tower", "rotators": ["upper", "lower"]}]}


def running_or_refused(b: Rig, app: App) -> None:
    if not app.failed.is_set():  # refused at once is the fix; started, its rotator answers
        wait_until(
            lambda: b.status("mast").available or app.failed.is_set(),
            what="the second bridge's rotator to answer",
        )


@pytest.mark.parametrize(
    "order",
    [
        "group first",  # fixed: the group's G/info names its bridge (claim rule 5)
        "group last",  # fixed: claim rule 5 reads a group's root as a rotator's
    ],
)
def test_a_bridge_on_another_bridges_group_topic_never_turns_on_its_targets(
    tmp_path: Path, broker: Mosquitto, probe: Probe, order: str
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        station_with_group(a)
        b.base = "rotor/tower"  # the second bridge's one rotator's topics are A's group's
        mast = b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        if order == "group first":
            first = a.start()
            a.ready("upper")
            a.ready("lower")
            probe.wait_value("rotor/tower/availability", "online")
            second = b.start()
            running_or_refused(b, second)
        else:
            first = b.start()
            b.ready("mast")
            second = a.start()
            wait_until(
                lambda: (
                    second.failed.is_set()
                    or (a.status("upper").available and a.status("lower").available)
                ),
                what="the group's bridge to refuse or run",
            )
        refused = second.failed.is_set()
        probe.publish("rotor/tower/target", "90")
        turned = b.emus["mast"] if order == "group last" and refused else a.emus["upper"]
        if order == "group first" or not refused:
            turned.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
            after = mast.state()
            assert (after.az_deg, after.is_moving) == (200, False), after
        else:
            mast.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
            assert a.emus["upper"].state().az_deg == 0
        assert refused and not first.failed.is_set()
