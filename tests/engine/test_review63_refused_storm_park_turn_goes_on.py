"""Review 63: a storm whose park is refused lets the turn under way go on to the operator's
target, while R/status says the rotor "stands where the storm found it".

52f0f8e0 gave a refused storm park its words: ``wind.refused`` (docs/mqtt.md: "the storm's park
was refused by the limits or a keep-out sector: the rotor stands where the storm found it,
motion refused all the same"), and every move refused with "motion refused for the storm (its
park refused: ...)". But nothing stops the turn the controller already had: the park that would
have replaced it is refused, no stop is sent, and the rotor runs on in the storm to the target
an operator gave before it (docs/wind.md rule 1 keeps a turn going only for a storm known from
a replay, which "sends nothing, not even a stop").

A Rotor-EZ under limits 20..340, its storm park at 30, turning from 100 to 330; the storm
begins as it passes 260 (from there the park is refused: its turn would pass north). In virtual
time."""

from __future__ import annotations

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

WIND = {
    "az_min_deg": 20,
    "az_max_deg": 340,
    "park_az_deg": 30,
    "wind_topic": "weather/wind",
    "wind_park_above": 60,
}
STORM_KMH = 90.0
STORM_S = 120.0  # virtual: a Rotor-EZ turns the last 70 degrees well inside this
BRAKE_DEG = 10.0  # what a stopped Rotor-EZ may run on, at most


def turned_to_rest(v: VirtualRotator, az_deg: float) -> None:
    """The controller answering, the rotor turned to ``az_deg`` and at rest there (the set-up of
    the refused storm park's tests: reviews 63, 65, 66)."""
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.target(az_deg)
    v.run_until(
        lambda h: abs(h.truth().az_deg - az_deg) < 1.0 and h.state is MotionState.IDLE,
        120,
        f"at rest at {az_deg:g}",
    )


def test_a_refused_storm_park_leaves_the_rotor_where_the_storm_found_it() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        turned_to_rest(v, 100.0)
        v.target(330.0)
        v.run_until(lambda h: h.truth().az_deg > 260.0, 120, "turning, past 260")
        found = v.truth().az_deg
        v.mailbox.put_wind(STORM_KMH)
        v._take()
        v.run_for(STORM_S)
        wind = v.status.wind
        assert wind is not None and wind.storm and wind.refused  # the park refused, said so
        az = v.truth().az_deg
        assert az - found < BRAKE_DEG, (
            f"the storm found the rotor at {found:.0f}; it turned on to {az:.0f} in the storm "
            f"under '{wind.refusal}'"
        )
