"""Review 95: docs/follow.md says "While following, the rotator does not park by itself", but
following switched on before WSJT-X says anything (or with its last status older than FRESH_S)
proposed nothing, not even activity: auto-park parked the rotor under the operator who had just
switched following on."""

from __future__ import annotations

from tests.engine.test_follow import bearing, spid
from tests.integration.test_pointing_bridge import angle_between


def test_following_switched_on_before_wsjtx_speaks_holds_auto_park_off() -> None:
    with spid(park_az_deg=0, park_after_idle_s=30) as v:
        v.target(90.0)
        v.run_until(lambda h: not h.truth().is_moving and h.truth().az_deg == 90.0, 60)
        v.follow(True)  # WSJT-X not started yet: nothing heard
        since = v.now
        v.run_for(300.0)
        assert v.frames("set", since=since) == [], "auto-park turned a rotor that is following"
        assert not v.status.parked and v.truth().az_deg == 90.0
        v.heard("JA1ABC", "PM95")  # WSJT-X comes up: following turns, as before
        v.run_for(60.0)
        assert angle_between(v.truth().az_deg, bearing("PM95")) <= 0.5
