"""Review 99: a controller that sends nothing but one stray byte is told to be at the wrong
baud rate, not to give no answer.

Commit 7ae864e1 (link.py rule 11, ``Link.fed``) counts bytes read since a question that the
codec made nothing of as a garbled answer, so that a box at the wrong baud rate is told
"answers only garbled replies: the wrong baud rate or model, or a noisy line?" (controller.py
rule 2) rather than "does not answer". A single byte is enough: a NUL that a USB adapter gives
as its port opens, or that a box's transmit line gives as it is switched off (its line
dropping to a break), is an answer of the first poll's, and the box switched off, the cable
pulled at its end, is told as set to the wrong baud rate. The user checks the settings, not
the box or the cable. Before the commit: "does not answer".

In virtual time: the box's first byte reaches the host as a NUL; nothing else ever does.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.virtual import VirtualRotator

STRAY = b"\x00"
TIMEOUT_S = 30  # the complaint at the silence timeout, with room (virtual time)


@pytest.mark.parametrize("model", ["gs232b", "easycomm2", "rc2800-az"])
def test_one_stray_byte_then_nothing_is_still_said_not_to_answer(
    rig: Callable[..., VirtualRotator], model: str
) -> None:
    v = rig(model, connect=False)
    strays: list[float] = []

    def one_stray(data: bytes, now: float) -> bytes:
        if strays:
            return b""
        strays.append(now)
        return STRAY

    v.to_host = one_stray
    v.link_up()
    v.run_until(lambda h: h.errors("serial"), TIMEOUT_S, "the complaint")
    assert strays
    why = v.errors("serial")[0].message
    assert why.endswith("does not answer") and "baud" not in why, why
    assert not v.status.available
