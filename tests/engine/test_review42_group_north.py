"""Review 42 of attack 10's group fix (groups.py rule 2, pointing.py rule 2): a group member's
bearing that its offset brings to north names neither end of its travel
(``Target.az_either_end``), and where 0 and 360 are the two ends (a GS-232) its judge takes
the end nearer the rotor. The judge takes it only where the bearing's raw value is exactly 0
or 360; one that the controller is sent as an end after its rounding (pointing.py rule 4: a
GS-232 takes whole degrees, half up) goes out as the end rule 2 gives the value as named. A
member in group ``stack`` with ``offsets = { lower = 180 }`` at 355 is sent the group's
180.4 as ``M000``, and one with ``lower = 179.6`` at 5 the group's 180 as ``M360``: each turns
the whole way round, 355 degrees, for a bearing 5 degrees away. What a user notices: the
antenna sweeps through south.
(Fixed: pointing.py ``_north_step`` takes the nearer end for any value sent as north after
its rounding, not on a SatEL alone.)"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import Target
from bridge.interfaces.mqtt.groups import Group, Member, fan_out
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
AZ_ONLY = {"upper": False, "lower": False}


def _swept(v: VirtualRotator, seconds: float) -> tuple[float, float]:
    """The lowest and highest raw azimuth the rotor turned through over ``seconds``."""
    low = high = v.truth().az_deg
    for _ in range(int(seconds)):
        v.run_for(1.0)
        low, high = min(low, v.truth().az_deg), max(high, v.truth().az_deg)
    return low, high


def _part(offset: float, payload: bytes) -> Target:
    stack = Group("stack", "Stack", (Member("upper"), Member("lower", offset)))
    part = fan_out(stack, payload, AZ_ONLY)[1].target
    assert part is not None and part.az_either_end
    return part


@pytest.mark.parametrize(
    ("offset", "payload", "start"),
    [(180.0, b"180.4", 355), (179.6, b"180", 5)],
    ids=["bearing-0.4-at-355", "bearing-359.6-at-5"],
)
def test_a_members_bearing_sent_as_north_turns_a_gs232_the_short_way(
    rig: Rig, offset: float, payload: bytes, start: int
) -> None:
    v = rig("gs232b-az", emulator={"start_az_deg": start})
    v.run_until(lambda h: h.status.raw_bearing_deg is not None, 10, "a reading")
    v.aim(_part(offset, payload))  # judged as the member's Rotator judges it
    low, high = _swept(v, 60)
    assert high - low <= 10.0, (
        f"the member at {start} turned through raw {low:g}..{high:g} for a bearing 5 degrees "
        f"away (sent {[f.data for f in v.frames('move')]})"
    )
