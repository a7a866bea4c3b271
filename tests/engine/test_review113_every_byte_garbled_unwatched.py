"""Review 113: a start whose every byte is garbled (its line ends too) gets its unwatched stop
only after 22 s: the Easycomm turning at the start runs from 150 past ``az_min_deg`` 60 down to
15 (review 107's defect, whose fix covers answers that still end as lines).

Commit 3acc6c92 counts "a poll answered garbled past parsing" toward controller.py rule 9's
unwatched stop (``_garbled_first``, on ``link.poll_garbled``). Review 107's line tore each
decimal point and kept the line ends: each poll's answer closes as a garbled one and eight are
counted in seconds. A receive line that garbles every byte (a failing RX level shifter, RF in
the cable: the host's own writes arrive intact) tears the line ends too: no answer ever
closes, the bridge says the controller "does not answer", as if silent (rule 2), though it reads
every byte, and counts nothing until its junk buffer spills 22 s later; by then the turn is 45
degrees past the limit. The parent ran it to its end.

In virtual time: review 107's start (the emulated Easycomm II box turning from 150 to 5 when the
bridge starts, ``az_min_deg`` 60); every byte it sends reaches the host XORed with 0x5A.

Fixed: link.py rule 11 counts a poll's answer torn past any form (half a reply's bytes or more
read, none forming a reply of the controller's, the second such exchange in a row) as garbled,
once per exchange: the unwatched stop comes after eight, within seconds.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import (
    stopped_before_the_limit,
    turning_at_the_start,
)
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def torn(data: bytes, now: float) -> bytes:
    """Every byte from the controller garbled (its line ends too): nothing parses."""
    return bytes(b ^ 0x5A for b in data)


def test_a_turn_whose_every_byte_is_garbled_is_stopped_before_the_limit(rig: Rig) -> None:
    v = turning_at_the_start(rig, "easycomm2", b"AZ5.0 EL0.0\n")
    stopped_before_the_limit(v, torn)
