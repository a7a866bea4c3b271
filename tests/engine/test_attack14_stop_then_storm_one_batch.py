"""Attack 14: a STOP (or a lock ON) taken before a storm's first reading, both in one batch of
the mailbox (the serial-lines thread served them in one round: it was busy with another port,
a write, a reply), is applied as if it had come in the storm: the session reads the batch's
wind first and its stop after, whatever order they were put in, so session/wind.py rule 3
("a stop or lock ON during a storm stops the park ... not tried again until the next storm")
takes a STOP that came before the storm for one that stopped its park. No park goes out for
the whole storm, motion is refused meanwhile (rule 1), so nobody can turn the antenna out of
the wind, and the status says "a stop or lock ON stopped its park" of a park that never was.
The same two commands taken one batch apart park the rotor (the control test below).

In virtual time, a Rotor-EZ at 90 with its storm park at 180."""

from __future__ import annotations

from bridge.core.model import MotionState, Stop
from tests.engine.virtual import VirtualRotator

WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180}
STORM_KMH = 90.0
PARK_TIME_S = 120.0  # virtual: a Rotor-EZ turns 90 degrees in well under this


def at_rest_at(v: VirtualRotator, az: float) -> bool:
    return abs(v.truth().az_deg - az) < 2.0 and v.state is MotionState.IDLE


def resting_at_90() -> VirtualRotator:
    v = VirtualRotator("rotorez", settings=WIND)
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.target(90.0)
    v.run_until(lambda h: at_rest_at(h, 90.0), 120, "at rest at 90")
    return v


def test_control_a_stop_then_a_storm_a_batch_apart_parks_for_the_storm() -> None:
    with resting_at_90() as v:
        v.stop()
        v.mailbox.put_wind(STORM_KMH)
        v._take()
        v.run_for(PARK_TIME_S)
        assert at_rest_at(v, 180.0)


def test_a_stop_put_before_the_storm_in_the_same_batch_still_parks_for_the_storm() -> None:
    with resting_at_90() as v:
        v.mailbox.put(Stop())  # the operator's STOP, at rest: nothing to stop
        v.mailbox.put_wind(STORM_KMH)  # then the storm's first reading
        v._take()  # one round of the serial-lines thread takes both
        v.run_for(PARK_TIME_S)
        wind = v.status.wind
        assert wind is not None and wind.storm
        assert not wind.halted, wind.refusal
        assert at_rest_at(v, 180.0), f"rotor at {v.truth().az_deg:.0f}, not at the storm park"


def test_a_lock_on_before_the_storm_in_the_same_batch_parks_at_the_lock_off() -> None:
    with resting_at_90() as v:
        v.mailbox.put_lock(True)
        v.mailbox.put_lock_saved(True)
        v.mailbox.put_wind(STORM_KMH)
        v._take()
        v.run_for(PARK_TIME_S)
        assert at_rest_at(v, 90.0)  # locked: nothing moves
        v.lock(False)  # the tower work is over; a storm begun under the lock parks now
        v.run_for(PARK_TIME_S)
        assert at_rest_at(v, 180.0), f"rotor at {v.truth().az_deg:.0f}, not at the storm park"


def test_control_a_lock_on_then_a_storm_a_batch_apart_parks_at_the_lock_off() -> None:
    with resting_at_90() as v:
        v.lock(True)
        v.mailbox.put_wind(STORM_KMH)
        v._take()
        v.run_for(PARK_TIME_S)
        assert at_rest_at(v, 90.0)
        v.lock(False)
        v.run_for(PARK_TIME_S)
        assert at_rest_at(v, 180.0)


def test_a_stop_put_after_the_storms_first_reading_in_the_same_batch_stops_its_park() -> None:
    """The batch's order both ways: a STOP put after the storm's first reading is a STOP in
    the storm (session/wind.py rule 3), though the two are taken in one round."""
    with resting_at_90() as v:
        v.mailbox.put_wind(STORM_KMH)  # the storm's first reading
        v.mailbox.put(Stop())  # then the operator's STOP
        v._take()
        v.run_for(PARK_TIME_S)
        wind = v.status.wind
        assert wind is not None and wind.storm and wind.halted
        assert at_rest_at(v, 90.0), f"rotor at {v.truth().az_deg:.0f}: the STOP was not heeded"
