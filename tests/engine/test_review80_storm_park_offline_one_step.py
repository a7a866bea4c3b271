"""Review 80: a storm's park the line took is not owed again when the controller answers at the
very next input after its offline.

wind.py rule 7: a park the line took from the rotator in a storm (a turn under way stopped at
the offline) is owed again, proposed once the controller answers. The session tells the wind
part so in ``_step`` (``self._answered and not ctl.answering``), *before* the step's own poll
(controller.py ``poll``) decides the offline, and sets ``_answered`` before that poll too. When
the reply that ends the offline comes as the next input (``bytes_received`` runs
``_answers_again`` before ``_step``), no step ever sees the controller not answering: ``lost``
is never called, the park is never sent again, and since 16eb7df1 (wind.py rule 10) the part
says "its park not reached" instead, for the whole storm. A line silent 4 s parks fine (steps
run meanwhile); one silent just the 3 s of ``silence_timeout_s`` does not.

Not new in 1222fcd3..45112209 (the same at 59e56d55); found by this review of wind.py rule 10
(which now keeps such a rotor off its park rather than saying it parked).

In virtual time, a Rotor-EZ at 30 with its storm park at 180."""

from __future__ import annotations

from tests.engine.test_review80_storm_park_power_cycle import storm_park_under_way
from tests.engine.virtual import VirtualRotator

WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180}
TURN_S = 200.0  # virtual: a Rotor-EZ turns 150 degrees in well under this


def test_a_storm_park_cut_by_a_short_offline_is_sent_again() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        storm_park_under_way(v)
        v.set_silent(True)  # the line drops the controller's replies ...
        v.run_until(lambda h: not h.status.available, 30, "offline (its turn stopped)")
        v.set_silent(False)  # ... and carries them again at once
        v.run_for(TURN_S)
        assert v.status.wind is not None and v.status.wind.storm  # the storm goes on
        assert abs(v.truth().az_deg - 180.0) < 2.0, (
            f"the rotor stands at {v.truth().az_deg:.0f}, its storm park is 180 (wind.py rule 7: "
            f"owed again); refusal: {v.status.wind.refusal!r}"
        )
