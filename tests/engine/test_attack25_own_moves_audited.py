"""Attack 25: a move of the bridge's own that no command started (the storm's park, auto-park's)
is one line in the audit trail, naming the feature (session.py rule 25): the session hands the
judge an ``Audit`` when it takes the park, once per park however many readings follow. (The
judge's line, in the audit file, with mosquitto and a pty:
tests/integration/test_attack25_auto_park_unaudited.py.) In virtual time, a Rotor-EZ."""

from __future__ import annotations

from bridge.core.model import MotionState, Origin, Source
from bridge.session.actions import Audit
from tests.engine.virtual import VirtualRotator

WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180}
SPELL = {"park_after_idle_s": 60, "park_az_deg": 0}
TURN_S = 120.0  # virtual: a Rotor-EZ turns 90 degrees in well under this


def at_rest_at(v: VirtualRotator, az: float) -> bool:
    return abs(v.truth().az_deg - az) < 2.0 and v.state is MotionState.IDLE


def test_a_storms_park_is_one_line_of_the_wind_in_the_audit_trail() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(90.0)
        v.run_until(lambda h: at_rest_at(h, 90.0), TURN_S, "at rest at 90")
        assert v.audited == []  # an operator's target: the judge's line, not the session's
        v.mailbox.put_wind(90.0)  # a storm
        v._take()
        v.run_until(lambda h: at_rest_at(h, 180.0), TURN_S, "at the storm's park")
        v.mailbox.put_wind(95.0)  # the storm goes on: no new park, no new line
        v._take()
        v.run_for(5.0)
        assert [a for _t, a in v.audited] == [Audit(Origin(Source.WIND), "park")]


def test_an_auto_park_is_one_line_of_auto_park_in_the_audit_trail() -> None:
    with VirtualRotator("rotorez", settings=SPELL) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(90.0)
        v.run_until(lambda h: at_rest_at(h, 90.0), TURN_S, "at rest at 90")
        assert v.audited == []
        v.run_until(lambda h: at_rest_at(h, 0.0), 60.0 + TURN_S, "auto-parked")
        v.run_for(120.0)  # parked: no park again, no line again
        assert [a for _t, a in v.audited] == [Audit(Origin(Source.AUTO_PARK), "park")]
