"""Attack 19: a pass tracked from its last minute (``R/track`` sent 20 s before LOS) ends, and
for the next 40 s the status says ``no pass`` while the next pass, 43 minutes on, is in view of
the search; the park after the pass (``track_at_los = "park"``) waits as long, and the rotor
turns on toward where the satellite set. skytrack.py ``searching``: a pass that is over is
dropped, but the next one is not searched for until PASS_RETRY_S after the search that found
the one over (rule 3 says it is searched for "once the pass in hand is over"); that search was
made at the start, 20 s before LOS. The sky is scripted (the test's own geometry)."""

from __future__ import annotations

from bridge.sky import Body, Sky
from tests.engine.test_attack19_wait_timed_at_full_speed import PASSES, T0, scripted_sky
from tests.engine.virtual import VirtualRotator
from tests.support.sky import synthetic_tle

LOS = PASSES[0][1]


def test_a_pass_tracked_from_its_last_minute_is_followed_by_the_next_one_at_once() -> None:
    line1, line2 = synthetic_tle(
        "TESTSAT", T0, inclination_deg=97.5, raan_deg=0.0, mean_anomaly_deg=0.0
    )
    settings = {"park_az_deg": 0, "park_el_deg": 0, "track_at_los": "park"}
    v = VirtualRotator("md01", sky=Sky(52.52, 13.29), wall_epoch_s=T0, settings=settings)
    v.answer_sky = scripted_sky
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
