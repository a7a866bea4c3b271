"""Attack 30: a line-ended controller whose every byte comes garbled (the wrong baud rate) is
told as one that "does not answer".

controller.py rule 2: "One that never gave a valid reply but garbled ones is said to (the wrong
baud rate looks so), not to give none", with words that point at the line's settings ("answers
only garbled replies: the wrong baud rate or model, or a noisy line?"). The test of it
(test_session_garbled.py) garbles a GS-232B's ``=`` and keeps its line ends. At the wrong baud
rate no byte comes as it was sent, the CR and LF that end a reply among them. The RT-21 and
Prosistel codecs report such bytes as noise at once and the words are right; the GS-232,
Easycomm and RC2800 codecs keep them, waiting for a line end, until 64 or 80 have come (more
than a silence timeout of polls): the bridge says "controller ... does not answer", and the
user looks at the cable, not at the baud rate.

In virtual time: every byte the box sends reaches the host as another (its top bit set and
its low bits flipped: no CR or LF ever comes), from the first.

Fixed (review 113's every-byte-garbled fix): link.py rule 11 counts an answer torn past any
form (half a reply's bytes or more, none forming a reply, two such exchanges in a row) as
garbled; a stray byte now and then (review 99) is still silence.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.virtual import VirtualRotator


def misread(data: bytes, now: float) -> bytes:
    """Each byte as a wrong baud rate reads it: another byte, never a line end."""
    return bytes((b ^ 0x5A) | 0x80 for b in data)


@pytest.mark.parametrize("model", ["gs232b", "easycomm2", "easycomm2-separate", "rc2800-az"])
def test_a_controller_at_the_wrong_baud_rate_is_said_to_answer_garbled(
    rig: Callable[..., VirtualRotator], model: str
) -> None:
    v = rig(model, connect=False)
    v.to_host = misread
    v.link_up()
    v.run_until(lambda h: h.errors("serial"), 30, "the complaint")
    why = v.errors("serial")[0].message
    assert "answers only garbled replies" in why and "baud" in why, why
    assert not v.status.available
