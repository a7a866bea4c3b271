"""Attack 10 on groups: a member's offset that brings the group's bearing to north. The group's
180 is north for a member with ``offsets = { lower = 180 }``; on a GS-232 (a RotorCard, a
SatEL, an Easycomm, a Prosistel, an RC2800 alike), whose 0 and 360 are the two ends of its
travel, north is the end nearer the rotor (pointing.py rule 2: 360 named is 360, 0 the other
end, a whole turn back; the loggers' ``heading`` takes the nearer). groups.py
``member_bearing`` folds 180 + 180 to 0, so the lower rotor at true 355, five degrees from
north, is sent ``M000`` and turns the whole way back through south; no group bearing names
360 for it."""

from __future__ import annotations

from tests.support.rig import Rig


def test_a_members_offset_to_north_turns_a_gs232_the_short_way(rig: Rig) -> None:
    rig.add("upper", model="gs232b-az", emu={"start_az_deg": 175})
    low = rig.add("lower", model="gs232b-az", emu={"start_az_deg": 355})
    rig.sections = {
        "groups": [{"id": "stack", "rotators": ["upper", "lower"], "offsets": {"lower": 180}}]
    }
    rig.start()
    rig.ready("upper")
    rig.ready("lower")
    rig.probe.publish("rotor/stack/target", "180")  # upper to 180; lower to north
    rig.arrived("upper", 180)
    rig.arrived("lower", 0)  # north, on either end of its scale
    assert [f.data for f in low.frames("move")] == [b"M360"], (
        "the lower rotor at 355 was sent the far end of its travel: a turn of 355 degrees "
        "through south for a bearing 5 degrees away"
    )
