"""Review 131: a controller at rest whose last few answers came garbled past parsing and that then
goes dead (a power cut: the answers torn as its supply sags, then nothing) is polled at the
moving rate for good once it is offline: an Easycomm II/III 150 frames a minute, an RT-21 200 and a
RotorCard 241 where the parent polls each 60 (its idle rate), a SatEL 30 where the parent polls it
15.

Commit 6f997233 (controller.py rule 9, ``_offline_phase``) lets the torn answers' count go on
while the controller is offline at rest, in ``poll`` too: from DOUBTS_TOLD (3) such answers on,
and until the eighth brings the unwatched stop, it is asked at the moving rate. A box that sends
nothing adds nothing to that count (the commit: "a box that sends nothing counts nothing"), so a
count left between three and seven when the box went dead stays there, and the moving rate with
it, for as long as the bridge runs. Rule 3: polling is idle work, slow when idle; rule 9: readings
at rest that disagree are asked at the moving rate "while it answers (review 40: offline,
idle)". The parent (befd8583) polls it at the idle rate once it is offline.

In virtual time: the emulated box at rest at 150, confirmed on a clean line; every byte it sends
XORed with 0x5A for TORN_S (a few torn answers, fewer than eight); then it sends nothing at all.
The frames written in one minute, DEAD_S on, are counted.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import confirmed_at_rest
from tests.engine.test_review113_every_byte_garbled_unwatched import torn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 100.0
CONFIRMED_S = 15.0  # the start's readings on a clean line (virtual time, not a deadline)
DEAD_S = 300.0  # long offline, nothing heard since (virtual time)
MINUTE_S = 60.0  # the minute whose frames are counted (virtual time)
SPARE = 2  # frames more than the idle rate makes in a minute, for the minute's edges


@pytest.mark.parametrize(
    ("model", "torn_s"),
    [
        ("easycomm2", 2.0),  # (four torn answers: 1.5 to 3 s gives 3-7)
        ("easycomm3", 2.0),  # (four)
        ("rt21", 1.75),  # (five: 1.25 to 2.5 s gives 3-7)
        ("rotorcard", 1.75),  # (five: 1.25 to 2.25 s gives 3-7)
        ("satel", 8.0),  # (four: 5 to 12 s gives 3-6)
    ],
)
def test_a_box_gone_dead_after_a_few_torn_answers_is_polled_at_the_idle_rate(
    rig: Rig, model: str, torn_s: float
) -> None:
    v = confirmed_at_rest(rig, model, REST_DEG, AZ_MIN_DEG, CONFIRMED_S)
    v.to_host = torn
    v.run_for(torn_s)
    v.to_host = None
    v.set_silent(True)  # (dead: nothing comes from it any more)
    v.run_for(DEAD_S)
    assert not v.status.available  # (offline, as it should be)
    t = v.now
    v.run_for(MINUTE_S)
    written = len(v.sent(since=t))
    idle = MINUTE_S / v.cfg.idle_poll_interval_s
    assert written <= idle + SPARE, (
        f"{model}: {written} frames written in a minute to a dead controller, offline at rest "
        f"{DEAD_S:g} s; its idle rate makes {idle:.0f}"
    )
