"""Review 125: the same as test_review125_every_byte_garbled_junk_stop_later.py at rest
(Medium): a line that garbles every byte (its line ends too) is promised offline at rule 2's
silence time, as review 118's at-rest test has it for GS-232 (3.4 s, as the same line
silent). On Rotor-EZ, RT-21, RC2800, Prosistel, MD-01 and Easycomm lines the garbled bytes
come as junk (NOISE), counted as garbled answers that keep the controller online for
GARBLED_SILENCE_FACTOR silence timeouts: it is shown online, at its last bearing, 6.2-6.65 s
(silent: 3.2-3.65 s); a Rot2Prog, whose silence time is 19 s, for 39.6 s (silent: 20.3 s).
Not a regression: 51a2f016 the same.

In virtual time: the emulated box at rest at 150; then every byte it sends reaches the host
XORed with 0x5A (review 113's ``torn``).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.test_review113_every_byte_garbled_unwatched import torn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
SETTLE_S = 60  # for the first readings to be taken, at rest (virtual time)
WATCH_S = 60.0  # the silence, the offline and what follows (virtual time)
STEP_S = 0.05  # a step of virtual time to see the offline: not a deadline


def offline_s(rig: Rig, model: str, fault: str) -> float | None:
    """How long after the line went bad (``fault``: every byte garbled, or silent) the
    controller was shown offline, at rest."""
    v = rig(model, emulator={"start_az_deg": REST_DEG})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    t = v.now
    if fault == "torn":
        v.to_host = torn
    else:
        v.set_silent(True)
    while v.now < t + WATCH_S:
        v.run_for(STEP_S)
        if not v.status.available:
            return v.now - t
    return None


@pytest.mark.xfail(
    strict=True,
    reason=(
        "review 125: a controller at rest on a line that garbles every byte is shown online "
        "twice rule 2's silence time (6.2-6.65 s; a Rot2Prog 39.6 s), on every model but GS-232"
    ),
)
@pytest.mark.parametrize(
    "model", ["rotorez", "rt21", "rc2800", "prosistel", "md01", "easycomm2", "rot2prog"]
)
def test_a_line_at_rest_that_garbles_every_byte_is_offline_at_the_silence_time(
    rig: Rig, model: str
) -> None:
    silent_s = offline_s(rig, model, "silent")
    assert silent_s is not None  # (rule 2: the silent controller goes offline)
    torn_s = offline_s(rig, model, "torn")
    assert torn_s is not None and torn_s <= silent_s + STEP_S, (
        f"offline {torn_s} s after the line went bad (silent: {silent_s:.2f} s)"
    )
