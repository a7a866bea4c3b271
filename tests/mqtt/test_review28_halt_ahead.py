"""Review 28 on runtime/rotator.py ``_halted`` (2b23241e: "a halt stamped ahead keeps a stamp
no later than when it came"): the stamp a move is compared with (``SentAt.unix``, service.py
rule 9) is clamped to the halt's arrival. A client that stamps by its own clock (docs/mqtt.md:
another client may stamp its commands; heartbeat.py rule 5 takes a stamp up to AHEAD_S ahead)
and runs 0.9 s fast stamps its move and its STOP alike: the move, sent 0.4 s before the STOP
and held up by its link, comes after the STOP stamped 0.4 s earlier than it, yet 0.5 s after
the clamped stamp, and is carried out after the STOP. Before 2b23241e the two stamps, one
clock, were compared as they came and the move was refused.

Note: the review-26 test (tests/mqtt/test_attack5_halt_stamp_ahead.py) asks the opposite of the
same numbers (a move stamped STOP - 0.4 by a right clock, sent after the STOP came, must pass):
the station cannot tell the two apart by the stamps alone. The project's rule is that a STOP
is the last word; the clamp trades that for the other sender's move.
"""

from __future__ import annotations

import math
import threading
from types import SimpleNamespace

from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.runtime.rotator import Rotator
from tests.mqtt.test_service import NOW_UNIX, service


def test_a_move_sent_before_a_stop_by_the_same_fast_clock_is_refused_after_it() -> None:
    svc, _pub, _rots = service({"tower": "rotorez"}, station="st1")
    judge = SimpleNamespace(
        last_halt_s=-math.inf, halted=(-math.inf, None), _halted_lock=threading.Lock()
    )
    fast = 0.9  # the sender's clock, ahead of the station's (within AHEAD_S: taken)
    stop = Stamp.of(NOW_UNIX + fast, 5.0, "st1")  # its STOP, sent now
    sent = svc._halt_sent_s(stop)  # noqa: SLF001
    assert sent is not None
    Rotator._halted(judge, sent)  # type: ignore[arg-type]  # noqa: SLF001
    # its move, sent 0.4 s before that STOP and held up on the way: stamped by the same clock
    move_stamp = NOW_UNIX + fast - 0.4
    assert move_stamp < float(stop.sent)  # (one clock: the move is the older)
    refused = svc._before_halt(move_stamp, judge)  # type: ignore[arg-type]  # noqa: SLF001
    assert refused, (
        "a move stamped 0.4 s before the STOP by the STOP's own clock is carried out after the "
        "STOP: the halt's stamp was clamped to its arrival"
    )
