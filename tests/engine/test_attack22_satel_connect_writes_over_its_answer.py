"""Attack 22: a SatEL's connect writes its clock line, ``g`` and ``z`` while the box is still
printing its answer to ``?``: the bridge's own half-duplex rule broken on the box that needs it.

The SatEL's line is half duplex to the bridge (protocols/satel.py: ``full_duplex`` False;
session/link.py rule 3: "nothing is written while a reply is owed, except a stop"), because the
box "does no input validation" and is driven one command and its answer at a time (satel.md
sections 5 and 6: Hamlib flushes, writes one command, reads its answer). At connect the codec's
frames (``s x ? t... g z``) go out in one breath: the 22-byte clock line arrives while the box
sends ``SatEL`` CR LF. The emulator takes both at once; a box whose firmware reads its input
while it is not printing loses part of the clock line (its clock then wrong, and the next
report's time with it). Low: what the real box does then is not documented.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_nothing_is_written_to_a_satel_while_it_answers_its_identify(rig: Rig) -> None:
    v = rig("satel")
    v.run_for(3)  # (the connect's exchanges: not a deadline)
    (at,) = [i for i, w in enumerate(v.writes) if w.data == b"?"]
    received, answered_t = b"", None
    for t, chunk in v.received:
        received += chunk
        if b"SatEL\r\n" in received:
            answered_t = t
            break
    assert answered_t is not None
    written_meanwhile = [w.data for w in v.writes[at + 1 :] if w.t < answered_t]
    assert written_meanwhile == [], written_meanwhile
