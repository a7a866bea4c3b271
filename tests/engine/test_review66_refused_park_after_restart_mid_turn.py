"""Review 66 (cold review of 0d66c42b, wind.py ``_turning``): a refused storm park stops the
bridge's own turn, "a target out, or one ``carried`` over a lost link". But ``carried`` is not
known yet when the park is judged right after a restart: the bridge restarted mid-turn (a
crash, a host that rebooted), a storm reading came in its first seconds, and the park owed is
judged at the first reading (wind.py rule 7), which finds the rotor where it is and cannot say
it turns (motion.py rule 4: a start's second reading says so, ``carried``). Refused there, the
turn the old process sent (to the operator's pre-storm target) is never stopped: the halt is
decided once, at the refusal, and the next reading, which shows the carried turn, judges
nothing again. The rotor runs on in the storm while R/status says it stands where the storm
found it (review 63's harm, after a restart).

A Rotor-EZ under limits 20..340, its storm park at 30 (refused from about 300: its turn would
pass north, as in review 65's files), turning from 200 to 335 when the bridge restarts near
290. In virtual time."""

from __future__ import annotations

from bridge.session.session import RotatorSession
from tests.engine.test_review63_refused_storm_park_turn_goes_on import (
    STORM_KMH,
    WIND,
    turned_to_rest,
)
from tests.engine.virtual import VirtualRotator

GONE_S = 1.0  # virtual: the bridge's process down
AFTER_S = 60.0  # virtual: the old turn over well inside this
OLD_DEG = 335.0  # the operator's target, before the storm


def test_a_park_refused_after_a_restart_mid_turn_stops_the_old_turn() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        turned_to_rest(v, 200.0)
        v.target(OLD_DEG)
        v.run_until(lambda h: h.truth().az_deg >= 285.0, 60, "turning past 285")
        v.link_down(None)  # the bridge's process gone mid-turn (no end, no stop)
        v.run_for(GONE_S)
        v.session = RotatorSession(v.cfg)  # the bridge started again
        v._do(v.session.start(v.now))
        v.mailbox.put_wind(STORM_KMH)  # a live storm reading in its first seconds
        v._take()
        v.link_up()
        v.run_for(AFTER_S)
        wind = v.status.wind
        assert wind is not None and wind.storm and wind.refused  # the park refused, said so
        az = v.truth().az_deg
        assert abs(az - OLD_DEG) > 5.0, (
            f"the park refused, the rotor should stand where the storm found it (~290); it ran "
            f"on to the pre-storm target, at {az:.0f} (sent {v.sent()[-5:]}) "
            f"under '{wind.refusal}'"
        )
