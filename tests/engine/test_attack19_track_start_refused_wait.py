"""Attack 19: a tracking start whose first target is the wait where the next pass rises, and
that wait is refused (the whole pass lies in a keep-out sector), leaves the turn under way to
the older target running. tracking.py rule 5 and docs/tracking.md ("Starting": "A first target
the limits or a keep-out sector refuse (``R/error`` says ``...; holding``) holds the rotor where
it is: a turn under way is stopped, once") hold for a start mid-pass (review 50) but not for a
start before the pass: ``_wait_for`` marks the first target put (``_last``) before ``_put``
judges it, so ``_put`` takes the start for a later step and halts nothing. A Rotor-EZ told to
track a satellite while it turned from 200 to 340 said "holding" and turned on 110 degrees to
the older target. The sky is scripted (the test's own geometry, no real sky)."""

from __future__ import annotations

import math

from bridge.core.model import ErrorKind
from bridge.sky import Body, Pass, Sky
from bridge.sky.worker import Answer, PassQuestion, PositionsQuestion, Question
from tests.engine.virtual import VirtualRotator
from tests.support.sky import synthetic_tle

T0 = 1_781_020_000.0  # the wall clock at the start (a fixed instant: the same sky every run)
AOS, LOS = T0 + 2000.0, T0 + 2300.0  # the next pass: half an hour on, azimuth 100 to 140


def _scripted_sky(q: Question) -> Answer:
    """A satellite whose one pass runs from azimuth 100 to 140 (elevation up to 30), below the
    horizon at 180 before and after it."""

    def at(t: float) -> tuple[float, float]:
        if AOS <= t <= LOS:
            f = (t - AOS) / (LOS - AOS)
            return 100.0 + 40.0 * f, 30.0 * math.sin(math.pi * f)
        return 180.0, -20.0

    if isinstance(q, PassQuestion):
        return Answer(
            q, Pass(AOS, LOS, (AOS + LOS) / 2, 30.0, 100.0, 140.0) if q.utc <= LOS else None
        )
    assert isinstance(q, PositionsQuestion)
    return Answer(q, [at(t) for t in q.times])


def rotorez_under_a_kept_out_pass() -> VirtualRotator:
    """A Rotor-EZ at 200 under the scripted sky, a keep-out sector (90 to 150) holding the whole
    pass (azimuth 100 to 140)."""
    v = VirtualRotator(
        "rotorez",
        sky=Sky(52.52, 13.29),
        wall_epoch_s=T0,
        emulator={"start_az_deg": 200.0},
        settings={"keep_out": [[90, 150]]},  # the whole pass is in it
    )
    v.answer_sky = _scripted_sky
    return v


def turning_toward_340(v: VirtualRotator) -> None:
    """The controller answering, its start's brake delay over, then sent to 340 and past 230."""
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.run_for(8.0)  # the Rotor-EZ's brake delay after its start is over
    v.target(340)
    v.run_until(lambda h: h.truth().az_deg >= 230.0, 60, "turning toward 340")


def test_a_track_start_whose_wait_for_the_pass_is_refused_stops_the_turn_under_way() -> None:
    line1, line2 = synthetic_tle(
        "TESTSAT", T0, inclination_deg=97.5, raan_deg=0.0, mean_anomaly_deg=0.0
    )
    with rotorez_under_a_kept_out_pass() as v:
        turning_toward_340(v)
        t, here = v.now, v.truth().az_deg
        v.track(Body.satellite("TESTSAT", line1, line2))
        v.run_for(60.0)  # (the old target is some 20 s on: not a deadline)
        assert v.status.tracking is not None  # taken, and holding
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message and "holding" in refused.message
        # held where it was (a stop and the Rotor-EZ's coast), not on to 340: observed 340
        assert abs(v.truth().az_deg - here) <= 15.0, (here, v.truth().az_deg)
