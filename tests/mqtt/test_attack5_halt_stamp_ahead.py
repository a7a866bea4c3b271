"""Attack pass 5 on service.py rule 9 / core/model.py ``SentAt`` / runtime/rotator.py
``_halted``: a halt's stamp is kept beside ``halted_s`` and a move's stamp is compared with it
directly. ``_halted`` clamps the steady time of a stamp ahead of its arrival to the arrival
("a sender's clock ahead cannot make older moves look stale"), but keeps the stamp itself
unclamped (``SentAt.unix``), and that is what moves are compared with. A STOP stamped up to
AHEAD_S (1 s) ahead passes the judge (a Node-RED flow's ``Date.now()/1000`` on a PC whose clock
runs 0.9 s fast; or a hostile client) and every stamped move sent in the next second (the
remote's operator's ``P`` right after their own ``S``, stamped never later than the truth) is
refused as "sent before the last STOP", while its client got RPRT 0. Repeated, each STOP
shadows the second after it; before this change the steady clock (clamped) decided.
"""

from __future__ import annotations

import math
import threading
import time
from types import SimpleNamespace

import pytest

from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.runtime.rotator import Rotator
from tests.mqtt.test_service import NOW_UNIX, service


@pytest.mark.xfail(
    strict=True,
    reason="review 28's policy: a halt stamped ahead refuses moves from a right clock for up "
    "to 1 s; the station cannot tell it from a fast-clocked sender's older move; refusing is "
    "the safe side (tests/mqtt/test_review28_halt_ahead.py)",
)
def test_a_move_sent_after_a_stop_stamped_ahead_is_not_refused_as_before_it() -> None:
    svc, _pub, _rots = service({"tower": "rotorez"}, station="st1")
    judge = SimpleNamespace(
        last_halt_s=-math.inf, halted=(-math.inf, None), _halted_lock=threading.Lock()
    )
    ahead = Stamp.of(NOW_UNIX + 0.9, 5.0, "st1")  # the STOP, stamped 0.9 s ahead
    sent = svc._halt_sent_s(ahead)  # noqa: SLF001
    assert sent is not None  # (within AHEAD_S: taken)
    Rotator._halted(judge, sent)  # type: ignore[arg-type]  # noqa: SLF001
    assert judge.halted[0] <= time.monotonic()  # (the steady time is clamped to arrival)
    # a move sent 0.5 s after the STOP came, by a sender whose clock is right
    refused = svc._before_halt(NOW_UNIX + 0.5, judge)  # type: ignore[arg-type]  # noqa: SLF001
    assert not refused, (
        "a move stamped after the STOP came is refused as sent before it: the STOP's stamp, "
        "0.9 s ahead, is compared unclamped (SentAt.unix)"
    )
