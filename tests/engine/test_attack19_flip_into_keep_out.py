"""Attack 19: the flip (tracking.py rule 4) is decided by the turning time of each way through
the pass, where a way the limits refuse counts as endless (``raw_for`` raises) but a way
through a keep-out sector counts as free: ``_flip_saves`` never asks the judge about sectors.
A pass running from 300 through the north to 60 on a 0..360 rotor whose elevation reaches 180,
with a keep-out sector 150..210 (a tower to the south): flown flipped, its azimuths run 120..240
through the sector, every step there is refused ("...; holding"), and the antenna stood at 150
while the satellite went on, off it by up to 60 degrees for 137 s of a 300 s pass. Not flipped,
the same pass costs one unwind at north (the sector may be swept through, pointing.py rule 3):
54 s off. A rotor that can flip did worse than the same rotor kept to 0..90 of elevation. The
sky is scripted (the test's own geometry); both rotors fly the same pass."""

from __future__ import annotations

import math

from bridge.sky import Body, Pass, Sky
from bridge.sky.worker import Answer, PassQuestion, PositionsQuestion, Question
from tests.engine.virtual import VirtualRotator
from tests.support.sky import synthetic_tle

T0 = 1_781_020_000.0  # the wall clock at the start (a fixed instant: the same sky every run)
AOS, LOS = T0 + 600.0, T0 + 900.0  # azimuth 300 to 60 through the north, elevation up to 30
SPEEDS = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
OFF_DEG = 10.0  # farther than this from the satellite is off it


def _satellite(t: float) -> tuple[float, float]:
    if AOS <= t <= LOS:
        f = (t - AOS) / (LOS - AOS)
        return (300.0 + 120.0 * f) % 360.0, 30.0 * math.sin(math.pi * f)
    return 180.0, -20.0


def _scripted_sky(q: Question) -> Answer:
    if isinstance(q, PassQuestion):
        return Answer(
            q, Pass(AOS, LOS, (AOS + LOS) / 2, 30.0, 300.0, 60.0) if q.utc <= LOS else None
        )
    assert isinstance(q, PositionsQuestion)
    return Answer(q, [_satellite(t) for t in q.times])


def _off(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def _seconds_off(el_max_deg: float) -> int:
    """The seconds of the pass a Rot2Prog limited to 0..360 (and 0..``el_max_deg``) points
    more than OFF_DEG from the satellite, the keep-out sector 150..210 configured."""
    line1, line2 = synthetic_tle(
        "TESTSAT", T0, inclination_deg=97.5, raan_deg=0.0, mean_anomaly_deg=0.0
    )
    limits = {"az_min_deg": 0, "az_max_deg": 360, "el_min_deg": 0, "el_max_deg": el_max_deg}
    v = VirtualRotator(
        "rot2prog",
        sky=Sky(52.52, 13.29),
        wall_epoch_s=T0,
        emulator=SPEEDS,
        settings={**SPEEDS, **limits, "keep_out": [[150, 210]]},
    )
    v.answer_sky = _scripted_sky
    off = 0
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.satellite("TESTSAT", line1, line2))
        v.run_until(lambda h: h.wall() >= AOS, 700, "AOS")
        while v.wall() < LOS:
            v.run_for(1.0)  # (a look a second: not a deadline)
            truth = v.truth()
            az, el = truth.az_deg, truth.el_deg or 0.0
            if el > 90.0:  # past the zenith it looks the other way
                az = (az + 180.0) % 360.0
            off += _off(az, _satellite(v.wall())[0]) > OFF_DEG
    return off


def test_a_rotor_that_can_flip_never_follows_a_pass_worse_for_a_keep_out_sector() -> None:
    unflipped = _seconds_off(90.0)  # cannot flip: one unwind at north
    assert unflipped <= 70  # (the unwind of 360 degrees at 6 a second, and its brake)
    assert _seconds_off(180.0) <= unflipped  # observed: 137
