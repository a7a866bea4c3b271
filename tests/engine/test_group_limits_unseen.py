"""A group's limits on a member's way (pointing.py rule 9) when the bridge cannot see where the
rotor is: a DCU-1 (it never answers) mounted south-centred (``az_offset_deg = 180``: its scale's
stop is at true south, so a turn on its scale can pass true north). In group ``stack`` with
``limits = { upper = [20, 340] }`` the upper antenna must stay out of 340..20 (docs/groups.md: "A
member's limits in the group hold on its way too ... a member whose only way there leaves
them refuses its part"). Without a reading the bridge cannot tell which way the turn goes: the
part must be refused, not sent."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import ErrorEvent, Target
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.session.motion import blind_busy_s
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_a_group_target_with_limits_is_refused_where_no_reading_shows_the_way(rig: Rig) -> None:
    # the antenna points true 300 (raw 120); the group's 30 is raw 210: 120 -> 210 on the
    # controller's scale is true 300 -> 390, through north, outside 20..340
    v = rig("dcu1", settings={"az_offset_deg": 180}, emulator={"start_az_deg": 120})
    cfg = v.cfg.motion
    v.run_for(blind_busy_s(cfg.az_span_deg, cfg) + cfg.brake_delay_s + 1)
    assert v.status.available and v.status.raw_bearing_deg is None
    t = v.now
    with pytest.raises(Refused) as refused:  # the group's part, judged as the Rotator does
        v.aim(Target(30.0, within_deg=(20.0, 340.0)))
    assert refused.value.code is RefusalCode.LIMITS
    v.run_for(60)
    assert [f.data for f in v.frames(since=t)] == []  # nothing sent to the controller
    assert v.truth().az_deg == 120  # the antenna never swept through north


@pytest.mark.parametrize(("start_raw", "group_az"), [(330, 0.0), (330, 360.0), (0, 310.0)])
def test_an_arc_that_ends_at_north_is_refused_where_no_reading_shows_the_way(
    rig: Rig, start_raw: int, group_az: float
) -> None:
    # a DCU-1 with no offset (its scale's stop at true north) in a group with
    # ``limits = { upper = [300, 360] }`` (groups.py rule 2 takes the group's 0 as 360 there):
    # the DCU-1 gets 360 as 000, so at true 330 the group's north turned it 330 -> 0 through
    # 300..0, and from raw 0 (true north, inside the arc) any turn goes round the other way
    v = rig("dcu1", emulator={"start_az_deg": start_raw})
    cfg = v.cfg.motion
    v.run_for(blind_busy_s(cfg.az_span_deg, cfg) + cfg.brake_delay_s + 1)
    assert v.status.available and v.status.raw_bearing_deg is None
    t = v.now
    with pytest.raises(Refused) as refused:
        v.aim(Target(group_az, within_deg=(300.0, 360.0)))
    assert refused.value.code is RefusalCode.LIMITS
    v.run_for(60)
    assert [f.data for f in v.frames(since=t)] == []
    assert v.truth().az_deg == start_raw


def test_an_arc_clear_of_north_and_south_is_kept_where_no_reading_shows_the_way(
    rig: Rig,
) -> None:
    # the same DCU-1 with limits 190..340: from inside the arc, no turn leaves it, whether its
    # scale's ends are at north or (a Hy-Gain rotor's stop) at south; 20..340 holds south,
    # where its stop is (protocols/rotorez.py), and 300 -> 30 may go through north
    v = rig("dcu1", emulator={"start_az_deg": 300})
    cfg = v.cfg.motion
    v.run_for(blind_busy_s(cfg.az_span_deg, cfg) + cfg.brake_delay_s + 1)
    with pytest.raises(Refused) as refused:
        v.aim(Target(30.0, within_deg=(20.0, 340.0)))
    assert refused.value.code is RefusalCode.LIMITS
    v.aim(Target(200.0, within_deg=(190.0, 340.0)))
    v.run_for(60)
    assert v.truth().az_deg == pytest.approx(200.0, abs=1.0)


def test_an_unplugged_member_s_part_is_refused_as_offline_not_as_its_limits(
    rig: Rig, tmp_path: Path
) -> None:
    """The judge every front end calls (runtime/rotator.py): a member with no reading because
    its link is down is refused as offline, not told of limits it has no reading to keep (a
    review: an unplugged south-centred DCU-1 got the limits' refusal, on its R/error and the
    group's G/error)."""
    v = rig("dcu1", settings={"az_offset_deg": 180}, emulator={"start_az_deg": 120})
    events: list[ErrorEvent] = []
    rot = Rotator(v.cfg, StateStore(tmp_path / "state.json"), lambda s: None, events.append)
    try:
        v.mailbox.close()  # the rotator's front half on this session (as test_halt_epoch's Bench)
        v.mailbox = rot._mailbox
        rot._worker.session = v.session
        v.link_down()
        v.run_until(lambda h: not h.status.available, 10, "offline")
        with pytest.raises(Refused) as refused:
            rot.submit(Target(30.0, within_deg=(20.0, 340.0)), "group stack: target 30")
        assert refused.value.code is RefusalCode.OFFLINE
        assert [e.message for e in events] == [
            "rotator offline (serial link down or controller silent)"
        ]
    finally:
        rot.operators.stop()


def test_a_hy_gain_rotors_way_across_north_is_held_to_the_groups_limits(rig: Rig) -> None:
    """An attack pass: a Rotor-EZ's Hy-Gain rotor has its stop at south (protocols/rotorez.py
    ``az_ends_at_north=False``, docs/pointing.md: north is mid-travel, ``+10`` from 355 goes
    out as 5, the turn across north). In a group with ``limits = { upper = [20, 340] }`` at 300,
    the group's 30 was taken as 300 -> 30 through south and sent (``AP1030``): the rotor, which
    cannot pass south, turns through north, the 340..20 the group keeps it out of. A scale whose
    ends are not known to be at north is judged both ways round (pointing.py rule 9)."""
    v = rig("rotorez", emulator={"start_az_deg": 300})
    v.run_until(lambda h: h.status.available and h.status.bearing_deg is not None, 10, "reads")
    t = v.now
    with pytest.raises(Refused) as refused:  # the group's part, judged as the Rotator does
        v.aim(Target(30.0, within_deg=(20.0, 340.0)))
    assert refused.value.code is RefusalCode.LIMITS
    assert "not reached from 300 without turning outside 20..340" in refused.value.message
    v.run_for(20)
    assert [f.data for f in v.frames(since=t) if f.data.startswith(b"AP1")] == []
    v.aim(Target(200.0, within_deg=(20.0, 340.0)))  # 300 -> 200: inside either way round
    v.run_until(lambda h: abs(h.truth().az_deg - 200.0) <= 1.0, 60, "turned to 200")
    assert [f.data for f in v.frames(since=t) if f.data.startswith(b"AP1")] == [b"AP1200\r"]
