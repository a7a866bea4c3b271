"""Review 118: review 113's fix (link.py rule 11: an answer torn past any form is garbled)
counts an answer torn only once TORN_SHARE of ``spec.reply_bytes`` has come, and
``reply_bytes`` is the model's LONGEST answer (Easycomm's ``AZ359.9 EL180.0`` LF, 16 bytes),
not the one under way. A controller at twice the configured baud rate (a SatNOGS box, 19200,
on a bridge set to K3NG's 9600) reaches the host as about every second byte, each garbled,
no line end among them: its answer at 150 degrees, ``AZ150.0 EL0.0`` LF, 14 bytes, arrives as
7, one short of half of 16. No answer is ever counted torn: the bridge says the controller
"does not answer" (silence, rule 2, not the wrong baud rate), counts nothing toward
controller.py rule 9's unwatched stop, and the turn under way at the start runs past
``az_min_deg`` to its end, unstopped: review 113's High, still open for this line.

The same start with every byte garbled one for one (review 113's own test) is stopped at 119.
A GS-232A azimuth box (``+0150`` CR LF, 7 bytes, read as 3 and 4 in turn: the 4 reach half of
7, the 3 do not, so no two torn answers ever come in a row) runs to its end likewise; so do
Easycomm III and the separate-line builds, and a Prosistel is stopped 15 s in, at 55.6, past
the limit (seen, not tested here). At rest the same line is told as silence ('does
not answer': the cable), not as garbled replies ('the wrong baud rate'), attack 30's words.

In virtual time: review 113's start (the emulated box turning from 150 to 5 when the bridge
starts, ``az_min_deg`` 60); every second byte it sends reaches the host, garbled.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import (
    START_DEG,
    WATCH_S,
    at_half_rate,
    stopped_before_the_limit,
    turning_at_the_start,
)
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.parametrize(
    ("model", "target"), [("easycomm2", b"AZ5.0 EL0.0\n"), ("gs232a-az", b"M005\r")]
)
def test_a_turn_read_at_half_rate_is_stopped_before_the_limit(
    rig: Rig, model: str, target: bytes
) -> None:
    v = turning_at_the_start(rig, model, target)
    stopped_before_the_limit(v, at_half_rate())


@pytest.mark.parametrize("model", ["easycomm2", "gs232a-az"])
def test_a_controller_read_at_half_rate_is_said_to_answer_garbled(rig: Rig, model: str) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG}, connect=False)
    v.to_host = at_half_rate()
    v.link_up()
    v.run_until(lambda h: h.errors("serial"), WATCH_S, "the complaint")
    why = v.errors("serial")[0].message
    assert "answers only garbled replies" in why and "baud" in why, why
