"""The bridge's own moves wait for a lock that is not known yet (runtime/kept.py rule 10,
parts.py rule 7): at a start whose state file did not say the rotator's lock, until the first
look hands on the ``R/lock/state`` the broker held, auto-park and a storm's park kept in the
state file send nothing; a lock ON heard then refuses them, and nothing heard lets them go.
(Someone may be on the tower: the lock ON was set for them, and the state file lost it.)"""

from __future__ import annotations

from bridge.core.model import MotionState
from bridge.session.session import RotatorSession
from tests.engine.virtual import VirtualRotator

AUTOPARK = {"park_az_deg": 0, "park_after_idle_s": 30}
WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180}


def started_unknown(
    model: str, settings: dict[str, object], *, storm: bool = False
) -> VirtualRotator:
    """A start whose state file did not say the lock (app.py: ``await_heard_lock`` before the
    port opens), at rest at 90; ``storm``: the state file kept a storm whose park was not seen
    reached (runtime/kept.py rule 4)."""
    v = VirtualRotator(model, settings=settings, emulator={"start_az_deg": 90}, connect=False)
    if storm:
        v.session = RotatorSession(v.cfg, storm=True)
        v._do(v.session.start(v.now))
    v.mailbox.put_lock_unknown(True)
    v._take()
    v.link_up()
    v.run_until(lambda h: h.status.available, 20, "the controller answers")
    return v


def unmoved(v: VirtualRotator) -> bool:
    """The rotor still at 90, never seen turning."""
    turned = [s for s in v.published() if s.state is MotionState.MOVING]
    return abs(v.truth().az_deg - 90.0) < 0.5 and not v.truth().is_moving and not turned


def heard(v: VirtualRotator, on: bool) -> None:
    """What the first look hands on (runtime/rotator.py ``heard_lock``): the broker's ON locks
    the rotator, anything else says the lock is known."""
    if on:
        v.lock(True)
    else:
        v.mailbox.put_lock_unknown(False)
        v._take()


def test_auto_park_waits_for_the_lock_and_a_heard_lock_on_refuses_it() -> None:
    with started_unknown("rotorez", AUTOPARK) as v:
        v.run_for(300.0)  # the broker away ten quiet spells long
        assert unmoved(v)
        assert v.status.lock_unknown
        heard(v, True)
        v.run_for(300.0)
        assert unmoved(v)


def test_auto_park_goes_once_the_broker_said_no_lock() -> None:
    with started_unknown("rotorez", AUTOPARK) as v:
        v.run_for(60.0)
        assert unmoved(v)
        heard(v, False)
        v.run_until(lambda h: h.status.parked, 120, "parked by itself")
        assert abs(v.truth().az_deg - 0.0) < 1.0


def test_a_kept_storm_park_waits_for_the_lock_and_a_heard_lock_on_refuses_it() -> None:
    with started_unknown("md01", WIND, storm=True) as v:
        v.run_for(120.0)
        assert unmoved(v)
        heard(v, True)
        v.run_for(60.0)
        v.lock(False)  # (wind.py rule 3: the lock ON stopped the park; it is not sent again)
        v.run_for(120.0)
        assert unmoved(v)
        assert v.status.wind is not None and v.status.wind.storm


def test_a_kept_storm_park_goes_once_the_broker_said_no_lock() -> None:
    with started_unknown("md01", WIND, storm=True) as v:
        v.run_for(30.0)
        assert unmoved(v)
        heard(v, False)
        v.run_until(lambda h: h.status.parked, 120, "parked for the storm")
        assert abs(v.truth().az_deg - 180.0) < 1.0 and v.state is MotionState.IDLE
