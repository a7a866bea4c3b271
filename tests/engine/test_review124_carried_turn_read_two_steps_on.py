"""Review 124 (cold review of motion.py rule 2 after 48918b44..2d0bfa69): a carried axis's
creep inside ``noise_deg`` counts as a move only if it crept CREEP_SHARE of the axis's slowest
"by what it turned at least, a reading's step less", timed from the last reading where it stood.
Read two steps on (a GS-232B: whole degrees, 2 degrees of noise), what it turned at least is one
step; a healthy azimuth turning at 0.3 or 0.4 of rule 6's slowest (above CREEP_SHARE, 0.25)
takes a little over a second from its last reading where it stood to its reading two steps on,
so that creep is no move, the step hold (one step at CREEP_SHARE of its slowest) is over by
then, and its rest is called between two of its moves past the noise: controller.py rule 13
stops the healthy turn short, R/error "rotor at rest ... short of its turn ... (jammed, stopped
at the panel, or its power cut meanwhile)". A K3NG answering late (polled slower) is stopped
short at every phase of the replug. Before this session (51a2f016) each case finished at its
target (bisected: 48918b44 for some, 766fa6eb for all). A turn as slow as these is one the rule
promises to leave to finish."""

from __future__ import annotations

from typing import Any

import pytest

from bridge.core.model import ErrorKind
from bridge.session import motion as mo
from tests.engine.carried import at_rest, replugged
from tests.engine.virtual import VirtualRotator

START_AZ = 20.0


@pytest.mark.parametrize(
    ("model", "share", "aim", "replugs", "out_s", "after_s", "extra"),
    [
        ("gs232b", 0.4, (250.0, None), 2, 2.2, 0.4, {}),  # (azimuth only; out twice)
        ("gs232b", 0.3, (250.0, None), 2, 2.2, 0.4, {}),
        ("gs232a-az", 0.4, (250.0, None), 2, 2.2, 0.4, {}),
        # K3NG's late answers: polled slower, every phase stopped short
        ("gs232b", 0.3, (200.0, 60.0), 1, 2.0, 1.0, {"processing_delay_s": 0.6}),
        ("gs232b", 0.35, (200.0, 60.0), 2, 2.3, 0.2, {"processing_delay_s": 0.6}),
    ],
)
def test_a_healthy_carried_turn_above_creep_share_is_left_to_finish(
    model: str,
    share: float,
    aim: tuple[float, float | None],
    replugs: int,
    out_s: float,
    after_s: float,
    extra: dict[str, Any],
) -> None:
    with VirtualRotator(model) as probe:
        slowest = mo.slowest_deg_s(probe.cfg.motion)
    assert share > mo.CREEP_SHARE  # (a turn, not a drift)
    emulator = extra | {"start_az_deg": START_AZ, "az_speed_deg_s": share * slowest["azimuth"]}
    if "elevation" in slowest:
        emulator |= {"start_el_deg": 0.0, "el_speed_deg_s": share * slowest["elevation"]}
    with VirtualRotator(model, emulator=emulator) as v:
        at_rest(v)
        v.target(*aim)
        v.run_until(lambda h: h.truth().az_deg >= START_AZ + 8.0, 60, "the azimuth turning")
        for n in range(replugs):
            replugged(v, out_s)
            v.run_for(after_s if n == replugs - 1 else 1.0)  # (its readings back: not a deadline)
        assert v.truth().is_moving  # it finishes its old turn by itself
        t = v.now
        v.run_until(lambda h: not h.truth().is_moving, 400, "the turn over")
        v.run_for(10.0)  # (its rest told: not a deadline)
        assert [e.message for e in v.errors(ErrorKind.STOP, since=t)] == []
        assert "stop" not in {f.outcome for f in v.frames(since=t)}
        assert v.truth().az_deg == pytest.approx(aim[0], abs=1.0)
        if aim[1] is not None:
            assert v.truth().el_deg == pytest.approx(aim[1], abs=1.0)
