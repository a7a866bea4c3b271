"""Review 80: a storm's park reached flickers off_park at every reading of a still rotor whose
readings wander within its noise.

45112209 (wind.py rule 10, ``_at``) judges "at the park" by ``tolerance_deg`` alone, to stop
off_park flickering in a Rotor-EZ's brake window. The motion machine never takes a still
rotor's readings wandering within ``noise_deg`` for movement (motion.py rule 5: away means
beyond ``tolerance_deg + noise_deg``); ``_at`` does. A Rotor-EZ (spec noise_deg 2) set to
``tolerance_deg = 1`` (the setting's own example) whose potentiometer reads 180 and 182 in turn
at rest at its park is said off it at every other reading: R/status's wind block republished
with ``off_park`` true/false each second, Home Assistant's "Parked for the storm" toggling
ON/OFF, the refusal alternating "parked for the storm" and "turned off its park after reaching
it" -- a hand turn nobody made.

In virtual time, a Rotor-EZ at 90 with its storm park at 180, its reading jitter 2 degrees."""

from __future__ import annotations

from bridge.core.model import MotionState
from tests.engine.test_review63_storm_park_held_said_parked import ha_parked
from tests.engine.virtual import VirtualRotator

WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180}
SETTINGS = {**WIND, "tolerance_deg": 1.0}  # (rotator.py's example for it)
JITTER = {"jitter_deg": 2}  # within the Rotor-EZ's noise_deg
TURN_S = 120.0  # virtual: a Rotor-EZ turns 90 degrees in well under this
PARKED_S = 60.0  # virtual: a minute at the park, still


def test_a_still_rotor_at_its_storm_park_is_never_said_off_it_for_its_reading_noise() -> None:
    with VirtualRotator("rotorez", settings=SETTINGS, emulator=JITTER) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(90.0)
        v.run_until(
            lambda h: abs(h.truth().az_deg - 90.0) < 3.0 and h.state is MotionState.IDLE,
            TURN_S,
            "at rest at 90",
        )
        v.mailbox.put_wind(90.0)  # the storm: its park to 180
        v._take()
        v.run_until(
            lambda h: h.state is MotionState.IDLE and abs(h.truth().az_deg - 180.0) < 0.5,
            TURN_S,
            "at rest at the park",
        )
        t = v.now
        v.run_for(PARKED_S)
        assert abs(v.truth().az_deg - 180.0) < 0.5 and not v.truth().is_moving  # still there
        said = [s.wind.off_park for s in v.published(since=t) if s.wind is not None]
        flips = sum(a != b for a, b in zip(said, said[1:], strict=False))
        assert not any(said) and ha_parked(v) == "ON", (
            f"a still rotor at its park: off_park {said.count(True)} times of {len(said)} "
            f"statuses in {PARKED_S:g} s, {flips} flips"
        )
