"""Attack 14: following WSJT-X on a rotator with ``bands`` turns the antenna to a partner the
program named on that band before it left it (session/follow.py rules 4 and 8).

The follower keeps "the newest status on one of its bands" (``_mine``) of any program, not
each program's newest: a program's later status on another band does not retire it. So
within FRESH_S (30 s) of a program moving its dial away, that old status is taken as "the QSO
under way on its band" although no program is on the band any more:

- switched on, a 20 m antenna whose only WSJT-X moved to 40 m 15 s ago turns to the grid it
  named on 20 m (rule 9: "a grid heard on another band ... moves nothing"; the newest status,
  the program's own, says 40 m);
- following rig1 on 40 m, with rig2 on 40 m until a few seconds ago and now on 15 m, the
  40 m antenna, when rig1 leaves 40 m too, turns to rig2's old 40 m partner.

Each is a turn of the rotor for a status the program itself has since overtaken: a stale
message moves a rotor. The controls show the same moments with a status that still stands.

In virtual time, an MD-01 (SPID) as tests/engine/test_follow.py drives it."""

from __future__ import annotations

from bridge.session.follow import Heard
from tests.engine.test_follow import FORTY, TWENTY, bearing, sets, spid
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between

FIFTEEN = 21_074_000
DECODE_PERIOD_S = 15.0  # virtual: one FT8 period between two statuses
TURN_TIME_S = 60.0  # virtual: an MD-01 at 10 degrees a second turns anywhere in this


def hear(v: VirtualRotator, heard: Heard) -> None:
    v.mailbox.put_heard(heard)
    v._take()


def test_control_switched_on_it_turns_to_the_qso_under_way_on_its_band() -> None:
    with spid(bands=["20m"]) as v:
        hear(v, Heard("JA1ABC", "PM95", False, "WSJT-X", TWENTY))
        v.run_for(DECODE_PERIOD_S)
        v.follow(True)
        v.run_for(TURN_TIME_S)
        assert angle_between(v.truth().az_deg, bearing("PM95")) <= 0.5


def test_switched_on_it_does_not_turn_to_a_grid_named_before_the_radio_left_its_band() -> None:
    with spid(bands=["20m"]) as v:
        hear(v, Heard("JA1ABC", "PM95", False, "WSJT-X", TWENTY))  # on 20 m: PM95
        v.run_for(DECODE_PERIOD_S)
        hear(v, Heard("W1AW", "FN31", False, "WSJT-X", FORTY))  # the same radio, now on 40 m
        v.run_for(DECODE_PERIOD_S / 3)
        v.follow(True)  # the 20 m antenna's following: no program is on 20 m
        v.run_for(TURN_TIME_S)
        assert sets(v) == 0, (
            f"turned to {v.truth().az_deg:.0f} (PM95 is {bearing('PM95'):.0f}) for a QSO the "
            "radio left 20 m from"
        )


def test_control_it_switches_to_the_program_that_is_still_on_its_band() -> None:
    """follow.py rule 8 as tests/engine/test_follow.py has it: rig2 still on 40 m."""
    with spid(bands=["40m"]) as v:
        v.follow(True)
        hear(v, Heard("W1AW", "FN31", False, "WSJT-X - rig1", FORTY))  # followed
        v.run_for(TURN_TIME_S)
        hear(v, Heard("VK2XYZ", "QF56", False, "WSJT-X - rig2", FORTY))
        v.run_for(DECODE_PERIOD_S / 3)
        hear(v, Heard("JA1ABC", "PM95", False, "WSJT-X - rig1", TWENTY))  # rig1 leaves 40 m
        v.run_for(TURN_TIME_S)
        assert angle_between(v.truth().az_deg, bearing("QF56")) <= 0.5


def test_it_does_not_switch_to_a_program_that_has_left_its_band_too() -> None:
    with spid(bands=["40m"]) as v:
        v.follow(True)
        hear(v, Heard("W1AW", "FN31", False, "WSJT-X - rig1", FORTY))  # followed
        v.run_for(TURN_TIME_S)
        frames = sets(v)
        hear(v, Heard("VK2XYZ", "QF56", False, "WSJT-X - rig2", FORTY))  # rig2 on 40 m...
        v.run_for(DECODE_PERIOD_S / 3)
        hear(v, Heard("ZL1AA", "RF70", False, "WSJT-X - rig2", FIFTEEN))  # ...now on 15 m
        v.run_for(DECODE_PERIOD_S / 3)
        hear(v, Heard("JA1ABC", "PM95", False, "WSJT-X - rig1", TWENTY))  # rig1 leaves 40 m
        v.run_for(TURN_TIME_S)
        assert sets(v) == frames, (
            f"turned to {v.truth().az_deg:.0f} (QF56 is {bearing('QF56'):.0f}), a partner "
            "rig2 named on 40 m before it moved to 15 m"
        )
