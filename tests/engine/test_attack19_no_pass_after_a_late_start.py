"""Attack 19: a pass tracked from its last minute (``R/track`` sent 20 s before LOS) ends, and
for the next 40 s the status says ``no pass`` while the next pass, 43 minutes on, is in view of
the search; the park after the pass (``track_at_los = "park"``) waits as long, and the rotor
turns on toward where the satellite set. skytrack.py ``searching``: a pass that is over is
dropped, but the next one is not searched for until PASS_RETRY_S after the search that found
the one over (rule 3 says it is searched for "once the pass in hand is over"); that search was
made at the start, 20 s before LOS. The sky is scripted (the test's own geometry)."""

from __future__ import annotations

import math

from bridge.sky import Body, Pass, Sky
from bridge.sky.worker import Answer, PassQuestion, PositionsQuestion, Question
from tests.engine.virtual import VirtualRotator
from tests.support.sky import synthetic_tle

T0 = 1_781_020_000.0  # the wall clock at the start (a fixed instant: the same sky every run)
PASSES = [(T0 + 100.0, T0 + 400.0, 100.0, 110.0), (T0 + 3000.0, T0 + 3300.0, 280.0, 290.0)]
LOS = PASSES[0][1]


def _at(t: float) -> tuple[float, float]:
    for aos, los, az0, az1 in PASSES:
        if aos <= t <= los:
            f = (t - aos) / (los - aos)
            return az0 + f * (az1 - az0), 30.0 * math.sin(math.pi * f)
    return 180.0, -20.0


def _scripted_sky(q: Question) -> Answer:
    if isinstance(q, PassQuestion):
        for aos, los, az0, az1 in PASSES:
            if q.utc <= los:
                return Answer(q, Pass(aos, los, (aos + los) / 2, 30.0, az0, az1))
        return Answer(q, None)
    assert isinstance(q, PositionsQuestion)
    return Answer(q, [_at(t) for t in q.times])


def test_a_pass_tracked_from_its_last_minute_is_followed_by_the_next_one_at_once() -> None:
    line1, line2 = synthetic_tle(
        "TESTSAT", T0, inclination_deg=97.5, raan_deg=0.0, mean_anomaly_deg=0.0
    )
    settings = {"park_az_deg": 0, "park_el_deg": 0, "track_at_los": "park"}
    v = VirtualRotator("md01", sky=Sky(52.52, 13.29), wall_epoch_s=T0, settings=settings)
    v.answer_sky = _scripted_sky
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.wall() >= LOS - 20.0, 600, "the pass's last 20 s")
        v.track(Body.satellite("TESTSAT", line1, line2))
        v.run_until(lambda h: h.wall() >= LOS + 60.0, 600, "a minute after LOS")
        phases = [
            (round(t + v.wall_epoch_s - LOS, 1), s.tracking.phase)
            for t, s in v.statuses
            if t + v.wall_epoch_s > LOS and s.tracking is not None
        ]
        # observed: "no pass" from LOS to LOS + 40 s, the next pass 43 minutes on
        assert phases and all(phase == "waiting" for _t, phase in phases), phases[:3]
