"""Attack 19: a follow start whose first grid the judge refuses (the partner in a keep-out
sector) leaves the turn under way to the older target running. docs/tracking.md ("Starting"):
"A first target the limits or a keep-out sector refuse (``R/error`` says ...) holds the rotor
where it is: a turn under way is stopped, once ... Following (``R/follow``) starts the same
way." Tracking does this (tracking.py rule 5, ``Proposal.halt``: review 50); following's refusal
(follow.py rule 5) proposes no halt. A Rotor-EZ turning from 62 to 182, told ``R/follow wsjtx``
with JA1ABC in PM95 (42 degrees, inside the sector 32..52) heard, said the refusal and turned on
105 degrees to the older target."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from tests.engine.test_follow import STATION, bearing
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between

PARTNER = bearing("PM95")  # 42.2 from the test station: JA1ABC's grid


def follower_by_a_keep_out(model: str) -> VirtualRotator:
    """Following the test station's partners, with a keep-out sector 10 degrees either side of
    PARTNER's bearing and the rotor starting 20 degrees past it."""
    sector = [round(PARTNER) - 10, round(PARTNER) + 10]
    emulator = {"start_az_deg": round(PARTNER) + 20}
    settings = {"keep_out": [sector]}
    return VirtualRotator(model, emulator=emulator, follow=STATION, settings=settings)


def turning_away_from_the_partner(v: VirtualRotator) -> None:
    """A turn to 140 degrees past PARTNER (never through the sector), 35 degrees from it."""
    v.target(round(PARTNER + 140.0))  # (never through the sector)
    v.run_until(lambda h: angle_between(h.truth().az_deg, PARTNER) >= 35.0, 30, "turning")


def test_a_follow_start_whose_first_grid_is_refused_stops_the_turn_under_way() -> None:
    with follower_by_a_keep_out("rotorez") as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_for(8.0)  # the Rotor-EZ's brake delay after its start is over
        turning_away_from_the_partner(v)
        t, here = v.now, v.truth().az_deg
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the old target is some 20 s on: not a deadline)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        assert v.status.following is not None  # taken, and waiting for a grid it may turn to
        # held where it was (a stop and the Rotor-EZ's coast), not on to 182: observed 182
        assert angle_between(v.truth().az_deg, here) <= 15.0, (here, v.truth().az_deg)
