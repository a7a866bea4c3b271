"""Review 60: the storm's park, waiting under the hold of a STOP put just before the storm (the
stop lane's marker, or the stop express's sync word: session.py rule 13, session/wind.py rule
8), still goes when that hold ends after the storm is over.

session/wind.py rule 8 (9edee2df) says the park "goes when the hold ends"; nothing drops it when
a calm reading ends the storm meanwhile (session.py ``_storm`` drops tracking's, following's and
auto-park's targets when a storm begins, and nothing when it ends). So the rotor turns to the
wind park after the storm, with no storm in its status and no command from anyone: docs/wind.md
says that once the storm is over "it stays where it is until one comes ... the reading that
ends a storm turns nothing". The express's hold has no clock (stops.py rule 5: a firewall that
dropped its flow held a target 45 s), and ``wind_hold_min`` may be as short as the station's
next reading. The clearing release of the same hold drops the park (wind.py's storm is over),
which shows what the ordinary release should do.

In virtual time, a Rotor-EZ at 90 with its storm park at 180 and a half-minute calm hold."""

from __future__ import annotations

import pytest

from bridge.core.model import MotionState, Source, Stop
from tests.engine.virtual import VirtualRotator

WIND = {
    "wind_topic": "weather/wind",
    "wind_park_above": 60,
    "park_az_deg": 180,
    "wind_hold_min": 0.5,
}
STORM_KMH, CALM_KMH = 90.0, 20.0
MARKER = 1
GUST_S = 5.0  # virtual: the storm's first reading to the calm's first
CALM_S = 40.0  # virtual: longer than wind_hold_min
PARK_TIME_S = 120.0  # virtual: a Rotor-EZ turns 90 degrees in well under this


def at_rest_at(v: VirtualRotator, az: float) -> bool:
    return abs(v.truth().az_deg - az) < 2.0 and v.state is MotionState.IDLE


def held_through_a_short_storm(v: VirtualRotator, express: bool) -> None:
    """At rest at 90: the operator's STOP with its hold, a storm whose park waits under that
    hold, and the storm over before the hold ends."""
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.target(90.0)
    v.run_until(lambda h: at_rest_at(h, 90.0), 120, "at rest at 90")
    if express:
        v.mailbox.put_express_hold(MARKER)  # the operator's STOP, by the stop express
        v.mailbox.put(Stop(Source.MQTT))
    else:
        v.mailbox.put(Stop(Source.MQTT), hold=MARKER)  # the operator's STOP, on the lane
    v._take()
    v.mailbox.put_wind(STORM_KMH)  # the storm's first reading: its park waits for the hold
    v._take()
    v.run_for(GUST_S)
    v.mailbox.put_wind(CALM_KMH)  # the calm begins
    v._take()
    v.run_for(CALM_S)
    v.mailbox.put_wind(CALM_KMH)  # ... and ends the storm
    v._take()
    v.run_for(GUST_S)
    wind = v.status.wind
    assert wind is not None and not wind.storm, "the storm is over"
    assert at_rest_at(v, 90.0)


@pytest.mark.parametrize("express", [False, True], ids=["lane", "express"])
def test_a_storm_park_waiting_under_a_hold_stays_put_once_the_storm_is_over(
    express: bool,
) -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        held_through_a_short_storm(v, express)
        if express:
            v.mailbox.put_express_release(MARKER)  # the express's word came back at last
        else:
            v.mailbox.put_release(MARKER)  # the main connection caught up at last
        v._take()
        v.run_for(PARK_TIME_S)
        assert at_rest_at(v, 90.0), (
            f"rotor turned to {v.truth().az_deg:.0f} after the storm was over "
            f"(last source {v.status.last_command_source})"
        )


def test_control_the_same_hold_ending_by_clearing_after_the_storm_moves_nothing() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        held_through_a_short_storm(v, express=False)
        v.mailbox.put_release(0, clear=True)  # the main connection dropped instead
        v._take()
        v.run_for(PARK_TIME_S)
        assert at_rest_at(v, 90.0)


def test_the_park_dropped_by_a_clearing_after_the_storm_is_not_said_as_a_target() -> None:
    """The bridge's own park, dropped, is no operator's target to send again (wind.py rule 1:
    a cold review, tracking's and auto-park's so dropped were said as targets nobody sent)."""
    with VirtualRotator("rotorez", settings=WIND) as v:
        held_through_a_short_storm(v, express=False)
        since = v.now
        v.mailbox.put_release(0, clear=True)  # the main connection dropped
        v._take()
        v.run_for(GUST_S)
        said = [(e.message, e.command) for e in v.errors("refused", since=since)]
        assert said == [], f"R/error: {said}"
