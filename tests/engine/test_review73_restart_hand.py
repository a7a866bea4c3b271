"""Review 73 (f33b510d with d609655e, parts.py rules 8 and 10): a follow start taken at a
restart's first reading now waits for the second reading to judge the turn it found
(``Before``), and its refused first grid owes a halt to whatever turn that reading shows. On a
Rot2Prog the second reading comes a whole idle poll later (some 6 s here; review 54 saw 9 s).
A hand at the panel in that time, the rotor at rest since long before the restart, is taken
for the earlier bridge's turn: not a hand, so following goes on, and the owed halt stops it a
few degrees into its turn. Before f33b510d following ended 'turned by hand' and the rotor went
where the hand sent it (as it still does on a Rotor-EZ, whose second reading comes 0.2 s on)."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from bridge.session.session import RotatorSession
from tests.engine.test_follow import STATION, bearing
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between


def _restarted_at_rest(v: VirtualRotator) -> None:
    """The rotor at rest for long, then the bridge started again (a new session, the link down
    for a second) and the controller answering it."""
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
    v.run_for(20.0)  # at rest for long (not a deadline)
    v.link_down(None)
    v.run_for(1.0)  # (not a deadline)
    v.session = RotatorSession(v.cfg)  # the bridge started again
    v._do(v.session.start(v.now))
    v.link_up()
    v.run_until(lambda h: h.status.available, 10, "the controller answers again")


def test_a_hand_at_the_panel_before_a_restarts_second_reading_is_a_hand() -> None:
    partner = bearing("PM95")  # 42.2 from the test station
    sector = [round(partner) - 10, round(partner) + 10]
    emulator = {"start_az_deg": round(partner) + 20}
    settings = {"keep_out": [sector]}
    with VirtualRotator("rot2prog", emulator=emulator, follow=STATION, settings=settings) as v:
        _restarted_at_rest(v)
        t, rest = v.now, v.truth().az_deg
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_until(lambda h: bool(h.errors(ErrorKind.REFUSED, since=t)), 10, "refused")
        v.run_for(2.0)  # (not a deadline)
        assert v.truth().az_deg == rest and not v.truth().is_moving  # (never moved)
        hand_to = round(partner + 140.0)  # (never through the sector)
        v.manual_rotate(hand_to)  # a hand at the panel
        v.run_until(lambda h: h.status.moving, 30, "the bridge sees the hand's turn")
        v.run_until(lambda h: not h.truth().is_moving, 120, "the hand's turn over")
        # observed: a stop 7 s after the restart, the rotor left at 67 (not 182), following on
        assert "stop" not in {f.outcome for f in v.frames(since=t)}
        assert angle_between(v.truth().az_deg, hand_to) <= 1.0, (hand_to, v.truth().az_deg)
        assert v.status.following is None and v.status.following_ended == "turned by hand"


def test_a_hand_before_a_restarts_second_reading_ends_an_accepted_follow_start() -> None:
    """The same judgement with nothing refused: a follow start waiting for its first grid at
    a restart's first reading. Before f33b510d the hand ended following 'turned by hand' at
    the second reading, and the rotor went where the hand sent it."""
    partner = bearing("PM95")  # 42.2 from the test station
    emulator = {"start_az_deg": round(partner) + 20}
    with VirtualRotator("rot2prog", emulator=emulator, follow=STATION) as v:
        _restarted_at_rest(v)
        rest = v.truth().az_deg
        v.follow(True)  # taken: waiting for WSJT-X
        v.run_for(2.0)  # (not a deadline)
        assert v.truth().az_deg == rest and not v.truth().is_moving  # (never moved)
        hand_to = round(partner + 140.0)
        v.manual_rotate(hand_to)  # a hand at the panel
        v.run_until(lambda h: h.status.moving, 30, "the bridge sees the hand's turn")
        v.run_for(3.0)  # (the hand's turn under way: not a deadline)
        v.heard("JA1ABC", "PM95")  # the next grid
        v.run_until(lambda h: not h.truth().is_moving, 300, "the rotor at rest")
        # observed: following on, the rotor turned back to the partner's 42 (not 182)
        assert angle_between(v.truth().az_deg, hand_to) <= 1.0, (hand_to, v.truth().az_deg)
        assert v.status.following is None and v.status.following_ended == "turned by hand"
