"""Review 80: a Rotor-EZ power-cycled while it turns to the storm's park.

The box's mains blip mid-park: its motor stops, it forgets its target, and it says so with its
power-on byte (controller.py rule 12, motion.py rule 11: the session *knows* the box restarted,
no stall is guessed). The storm's park is the bridge's own move, and nobody can send it again
in the storm (wind.py rule 1: every motion command is refused).

16eb7df1 (wind.py rule 10) rewrites the end of a motion event's error for the storm's
park, "send the target again" to session.py's ``PARK_NOT_AGAIN``, but only for a STALLED
report ending with stops.py's ``SEND_AGAIN``: the restart's error (stops.py ``RESTARTED``,
kind ``serial``; the SatEL's clock gone back, controller.py ``Forgot``, alike) spells the
words out itself and still tells the user to send a target the storm refuses.

In virtual time, a Rotor-EZ at 30 with its storm park at 180."""

from __future__ import annotations

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180}
TURN_S = 200.0  # virtual: a Rotor-EZ turns 150 degrees in well under this
AFTER_S = 400.0  # virtual: long enough for any park sent again to arrive


def storm_park_under_way(v: VirtualRotator) -> None:
    """The rotor at rest at 30, then the storm's park to 180 under way (past 80)."""
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.target(30.0)
    v.run_until(
        lambda h: abs(h.truth().az_deg - 30.0) < 2.0 and h.state is MotionState.IDLE,
        TURN_S,
        "at rest at 30",
    )
    v.mailbox.put_wind(90.0)  # the storm: its park to 180
    v._take()
    v.run_until(
        lambda h: h.truth().is_moving and h.truth().az_deg > 80.0, TURN_S, "the park under way"
    )


def power_cycled_mid_park(v: VirtualRotator) -> None:
    storm_park_under_way(v)
    v.power_cycle()  # a mains blip: the box restarts, its power-on byte comes
    v.run_for(AFTER_S)


def test_a_restart_mid_storm_park_never_says_send_the_target_again() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        power_cycled_mid_park(v)
        said = [e.message for e in v.errors() if "restarted" in e.message]
        assert said, "the restart was said"
        v.target(100.0)  # what the error told the user to do: refused for the storm (parked
        assert v.errors("refused")[-1].message.endswith("for the storm")  # again, by then)
        assert not any(m.endswith("send the target again") for m in said), (
            f"R/error told the user to send the storm's park again, which the storm refuses: {said}"
        )


def test_a_storm_park_a_known_restart_cut_short_is_sent_again() -> None:
    """Wind.py rule 7 sends again a park the line took; rule 10 keeps back only a park whose
    motor drove against a jam. The power-on byte says neither: the box lost the park, its motor
    is free, and nobody else can send the park in the storm. (Not new in 1222fcd3..45112209:
    the same before 16eb7df1; found by this review.)"""
    with VirtualRotator("rotorez", settings=WIND) as v:
        power_cycled_mid_park(v)
        assert v.status.wind is not None and v.status.wind.storm  # the storm goes on
        assert abs(v.truth().az_deg - 180.0) < 2.0, (
            f"the rotor stands at {v.truth().az_deg:.0f}, its storm park is 180; R/status "
            f"wind: off_park={v.status.wind.off_park}; R/error: {[e.message for e in v.errors()]}"
        )
