"""Review 65: a storm whose park was refused, the line lost a moment, stops the operator's hand
turn on the front panel when the controller answers again.

4292601a made a refused storm park stop "the turn under way" (wind.py rule 5: the park would
have replaced it; the turn the storm found). But a park refused is owed again after an offline
(wind.py rule 7, ``lost``) and judged again at the controller's first reading since: refused
again, it stops whatever turns then. In a storm motion is refused to every interface, so the
only turn then is one the bridge did not send: the operator's, on the front panel, begun after
the storm found the park refused (docs/wind.md: "the rotor stands where the storm found it";
the operator turns it out of the wind by hand). A USB blip mid-turn, and the bridge sends a
stop that cuts that turn short where it stands, unsaid (R/error repeats "wind park refused").

A Rotor-EZ under limits 20..340, its storm park at 30, at rest at 300 (from there the park is
refused: its turn would pass north). The storm; the operator turns the rotor by hand to 200;
the port drops for 2 s mid-turn. In virtual time."""

from __future__ import annotations

from tests.engine.test_review63_refused_storm_park_turn_goes_on import (
    STORM_KMH,
    WIND,
    turned_to_rest,
)
from tests.engine.virtual import VirtualRotator

JUDGED_S = 30.0  # virtual: the storm's park judged and refused well inside this
TURNING_S = 3.0  # virtual: the hand turn under way (a Rotor-EZ turns 100 degrees in ~ 25 s)
BLIP_S = 2.0  # virtual: the USB line out
AFTER_S = 60.0  # virtual: the hand turn over well inside this
HAND_DEG = 200.0


def test_a_refused_storm_park_judged_again_leaves_a_hand_turn_alone() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        turned_to_rest(v, 300.0)
        v.mailbox.put_wind(STORM_KMH)
        v._take()
        v.run_for(JUDGED_S)
        wind = v.status.wind
        assert wind is not None and wind.storm and wind.refused  # the park refused, said so
        v.manual_rotate(HAND_DEG)  # the operator, at the panel, turns it out of the wind
        v.run_for(TURNING_S)
        v.link_down()
        v.run_for(BLIP_S)
        v.link_up()
        v.run_for(AFTER_S)
        az = v.truth().az_deg
        assert abs(az - HAND_DEG) < 1.0, (
            f"the operator turned the rotor by hand to {HAND_DEG:.0f}; the bridge stopped it "
            f"at {az:.0f} (sent {[w for w in v.sent() if w == b';']}) under '{wind.refusal}'"
        )
