"""Review 50 (cold review of the tracking start mid-turn, d2067f87..f87b1948): a tracking start
whose first target the judge refuses (the body in a keep-out sector; tracking.py rule 5: "the
rotor holds until the body is back where it may go", R/error says "...; holding") leaves the
turn under way to the older target running: the start was taken (tracking on, the status
says so, the old target no longer named in it), but no target of its own went out, so nothing
stopped that turn. The review 46 symptom again, by another door: a Rotor-EZ told ``track sun``
while it turned to a bearing 120 degrees from the sun turned on all the way there, "holding",
and the sun, once out of the sector, is some 110 degrees back. Every other newest command
takes the turn's place (docs/tracking.md, "Starting": "whatever the rotor was doing")."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from bridge.sky import Body, Sky
from tests.engine.test_session_tracking import SUN_EPOCH, off_deg, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.support.sky import sun_altaz


def test_a_tracking_start_whose_first_step_is_refused_holds_the_rotor_where_it_is() -> None:
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    sun_az = sun_altaz(lat, lon, wall)[0]
    away = sun_az - 120.0 if sun_az > 180.0 else sun_az + 120.0  # never across north
    sector = [round(sun_az) - 10, round(sun_az) + 10]  # the sun in it for the whole test
    toward = 20.0 if away > sun_az else -20.0  # (never through the sector)
    emulator = {"start_az_deg": round(sun_az + toward)}
    settings = {"keep_out": [sector]}
    with VirtualRotator(
        "rotorez", sky=Sky(lat, lon), wall_epoch_s=wall, emulator=emulator, settings=settings
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        v.run_for(6.0)  # the Rotor-EZ's brake delay after its start is over
        v.target(round(away))
        v.run_until(lambda h: off_deg(h.truth().az_deg, sun_az) >= 30.0, 30, "turning away")
        t, here = v.now, v.truth().az_deg
        v.track(Body.sun())
        v.run_for(60.0)  # (the old target is some 15 s on: not a deadline)
        assert v.status.tracking is not None  # taken, and holding
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message and "holding" in refused.message
        assert off_deg(v.truth().az_deg, here) <= 15.0  # observed: on to the old target
