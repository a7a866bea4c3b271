"""Review 136 (5): review 129's burst (the first byte of each answer line with its top bit
set, for 4.5 s) stops an Easycomm II or III az/el turn short, its target dropped, 'answers only
garbled replies', 3.6 s into the burst; link.py rule 11 (b28cd556) promises of such a burst
'a turn through a 4.5 s burst of those reaches its target', and review 129's guard test holds
it for GS-232B, RC2800 and Prosistel only (and it holds on GS-232A, RC2800 azimuth, Combi-Track,
the Easycomm azimuth and ``-separate`` models). The Easycomm codec reads ``\\xc1Z123.4 EL45.0``
as junk in front of an elevation (``_REPLY``'s ``pre``): an elevation alone, the query still
waiting for its azimuth, and no junk handed over at all, so nothing says the controller
answered and the turn is stopped at rule 2's silence time. Not a regression of b28cd556:
its parent and dd1e5dce the same.

In virtual time: the emulated box turning from 20 to 300, watched, then review 129's burst
(``first_byte_of_each_line_off``) for BURST_S.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import reached_through_the_burst, turning_for_a_burst
from tests.engine.test_review129_one_byte_off_answers_mid_turn_stopped import (
    BURST_S,
    START_DEG,
    WATCH_S,
    first_byte_of_each_line_off,
)
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.xfail(
    strict=True,
    reason="review-136 5: an Easycomm az/el turn through a 4.5 s burst of answers one byte "
    "off is stopped short at the silence time (the line read as an elevation alone)",
)
@pytest.mark.parametrize("model", ["easycomm2", "easycomm3"])
def test_an_easycomm_turn_through_a_burst_of_answers_one_byte_off_reaches_its_target(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    t = turning_for_a_burst(v)
    v.to_host = first_byte_of_each_line_off(t + BURST_S)
    v.run_for(WATCH_S)
    reached_through_the_burst(v, t)
