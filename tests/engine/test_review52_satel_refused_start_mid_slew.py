"""Review 52 (cold review of 7447112e, tracking.py rule 5): a tracking start whose first target
is refused stops the turn under way (``Proposal.halt``) "while no target of the start has been
put": ``_turning`` takes a SatEL's slew (``scene.slewing``) for a turn under way whether or not
a stop is already out, and ``_halt`` sends a new stop each time (stops.py: unmerged). A SatEL
slewing when ``track sun`` arrives, the sun in a keep-out sector: the first stop ends the slew,
but the bridge keeps its silent slew open until it may ask again (slew.py), tracking's next
step halts again, and the next, and the next: a stop some five times a second for as long as
the sun stays in the sector, never a status asked, the rotator shown "moving" for good. Before
7447112e nothing was sent (the old target turned on to). The SatEL takes a stop while it slews
(its only input then), so nothing is misused on the wire: what a user notices is the status
frozen on "moving" and the line full of stops."""

from __future__ import annotations

from bridge.core.model import Target
from bridge.sky import Body, Sky
from tests.engine.test_composite import FAST
from tests.engine.test_session_tracking import SUN_EPOCH, off_deg, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite
from tests.support.sky import sun_altaz


def test_a_satel_slewing_when_a_refused_tracking_start_comes_is_stopped_once_and_seen_at_rest() -> (
    None
):
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    sun_az = sun_altaz(lat, lon, wall)[0]
    away = sun_az - 120.0 if sun_az > 180.0 else sun_az + 120.0  # never across north
    toward = 20.0 if away > sun_az else -20.0  # (never through the sector)
    settings = {"keep_out": [[round(sun_az) - 10, round(sun_az) + 10]]}  # the sun in it
    with VirtualRotator("satel", sky=Sky(lat, lon), wall_epoch_s=wall, settings=settings) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 60, "at rest")
        v.target(round(sun_az + toward))
        v.run_until(lambda h: not h.status.moving and h.status.target_az_deg is None, 120, "there")
        v.target(round(away))
        v.run_until(lambda h: off_deg(h.truth().az_deg, sun_az) >= 30.0, 60, "slewing away")
        t = v.now
        v.track(Body.sun())
        v.run_for(60.0)  # (a slew's longest is some 40 s: not a deadline)
        assert v.status.tracking is not None  # taken, and holding
        assert not v.truth().is_moving  # stopped: the halt did its work
        stops = v.frames("stop", since=t)
        assert len(stops) <= 2, len(stops)  # observed: some 300
        assert v.frames("status", since=t) != []  # observed: never asked again
        assert not v.status.moving  # observed: "moving" for good


def test_a_composites_satel_box_slewing_when_a_refused_tracking_start_comes_is_stopped_once() -> (
    None
):
    """The same on a rotator of two boxes: an RT-21 azimuth box and a SatEL elevation box,
    both turning to an older target when ``track sun`` comes, the sun in a keep-out sector.
    Each box's tracking refuses and halts; the RT-21 takes one stop, the SatEL some 300."""
    lat, lon = sun_up_somewhere(SUN_EPOCH, 20.0, 50.0)
    sun_az = sun_altaz(lat, lon, SUN_EPOCH)[0]
    away = sun_az - 120.0 if sun_az > 180.0 else sun_az + 120.0  # never across north
    settings = {"keep_out": [[round(sun_az) - 10, round(sun_az) + 10]]}  # the sun in it
    with VirtualComposite(
        "rt21",
        "satel",
        settings=settings,
        emulators=FAST,
        sky=Sky(lat, lon),
        wall_epoch_s=SUN_EPOCH,
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(round(away), 80.0))
        v.run_until(lambda h: h.el.truth().is_moving, 10, "the elevation box slewing")
        t = v.now
        v.track(Body.sun())
        v.run_for(60.0)  # (a slew's longest is some 40 s: not a deadline)
        assert v.status.tracking is not None  # taken, and holding
        assert len(v.az.frames("stop", since=t)) <= 2  # (the RT-21: one)
        stops = v.el.frames("stop", since=t)
        assert len(stops) <= 2, len(stops)  # observed: some 300
        assert v.el.frames("status", since=t) != []  # observed: never asked again
