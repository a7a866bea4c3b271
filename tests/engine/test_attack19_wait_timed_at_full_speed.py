"""Attack 19: tracking times its move to the next pass's rise (tracking.py rule 2: "when the
rotor, at its real speeds, would just make it in time plus PREPOSITION_MARGIN_S") by the
configured speeds, never by the speed the controller was last set to. docs/architecture.md
("Controller settings as data", ``speed_factors``) says the rotor's speeds in every travel
estimate are the configured ones times the factor of the value last sent, and the controller
retunes its own (controller.py ``_retune``), but the Tracker keeps the configuration it was
made with. A GS-232B set to speed 1 (``R/option/speed``, a quarter of full speed) left for a
pass rising 171 degrees away at the moment full speed would have needed (AOS - 48 s, as with
speed 4), and at AOS it stood at 181, turning, 99 degrees from the satellite: 66 s of a 300 s
pass lost, with nothing said. The sky is scripted (the test's own geometry, no real sky)."""

from __future__ import annotations

import math

from bridge.sky import Body, Pass, Sky
from bridge.sky.worker import Answer, PassQuestion, PositionsQuestion, Question
from tests.engine.virtual import VirtualRotator
from tests.support.sky import synthetic_tle

T0 = 1_781_020_000.0  # the wall clock at the start (a fixed instant: the same sky every run)
# (AOS, LOS, azimuth at AOS, at LOS): the first pass ends near 110, the next rises at 280
PASSES = [(T0 + 100.0, T0 + 400.0, 100.0, 110.0), (T0 + 3000.0, T0 + 3300.0, 280.0, 290.0)]


def _at(t: float) -> tuple[float, float]:
    for aos, los, az0, az1 in PASSES:
        if aos <= t <= los:
            f = (t - aos) / (los - aos)
            return az0 + f * (az1 - az0), 30.0 * math.sin(math.pi * f)
    return 180.0, -20.0


def scripted_sky(q: Question) -> Answer:
    """The sky of PASSES: the sky worker's answers, scripted (no real sky)."""
    if isinstance(q, PassQuestion):
        for aos, los, az0, az1 in PASSES:
            if q.utc <= los:
                return Answer(q, Pass(aos, los, (aos + los) / 2, 30.0, az0, az1))
        return Answer(q, None)
    assert isinstance(q, PositionsQuestion)
    return Answer(q, [_at(t) for t in q.times])


def test_a_gs232_set_to_its_slowest_speed_is_at_the_next_pass_when_it_rises() -> None:
    line1, line2 = synthetic_tle(
        "TESTSAT", T0, inclination_deg=97.5, raan_deg=0.0, mean_anomaly_deg=0.0
    )
    v = VirtualRotator(
        "gs232b-az",
        sky=Sky(52.52, 13.29),
        wall_epoch_s=T0,
        options={"speed": "1"},  # R/option/speed 1, as the state file keeps it
        emulator={"start_az_deg": 100.0},
    )
    v.answer_sky = scripted_sky
    aos = PASSES[1][0]
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.satellite("TESTSAT", line1, line2))
        v.run_until(lambda h: h.wall() >= PASSES[0][1] + 100.0, 600, "the first pass over")
        assert v.truth().speed_level == 1  # the box turns at a quarter of its speed
        v.run_until(lambda h: h.wall() >= aos, 3000, "the next pass rises")
        truth = v.truth()
        # at the rise, still (observed: at 181, turning toward 280)
        assert abs(truth.az_deg - 280.0) <= 3.0 and not truth.is_moving, truth
