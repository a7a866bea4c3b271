"""Review 154 (3f19928d: the stop express's reader sleeps while nothing waits): the tick's
verdict "nothing waits" is read in two steps, the holds first (none), then whether a word sent
is unread. A hold put between the two, whose request ``_Outbox.ask`` leaves out (the last word
sent, a vouch's request, is still unread: rule 8), sends nothing and so wakes nothing; the
child then reads that word, the second step finds nothing unread, and the reader sleeps with
the hold waiting. A broker that drops the sync word (the case RESEND_S is for) then leaves the
rotator's targets held for good: no word asked for again, no long hold said, until some other
word happens to be sent to the child."""

from __future__ import annotations

import os
import signal
import sys
import threading
from typing import Any

import pytest

import bridge.interfaces.mqtt.express as express_module
from bridge.interfaces.mqtt.express import LONG_HOLD_S, RESEND_S
from tests.mqtt.test_express import Holds, Problems, reader_asleep, up_on_a_fake_clock
from tests.support.waiting import wait_until

READS_WHEN_TOLD_ANSWERS_NOTHING = (  # up; reads nothing until SIGUSR1, then all, answers none
    "import signal, socket, sys\n"
    "s = socket.socket(fileno=int(sys.argv[-1]))\n"
    "s.recv(65536)\n"
    "signal.pthread_sigmask(signal.SIG_BLOCK, [signal.SIGUSR1])\n"
    's.send(b\'{"op": "up"}\')\n'
    "signal.sigwait([signal.SIGUSR1])\n"
    "while s.recv(65536):\n"
    "    pass\n"
)


def test_a_hold_put_while_the_reader_judges_nothing_waits_is_still_looked_at(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    problems, holds, now = Problems(), Holds(), [1000.0]
    cmd = [sys.executable, "-c", READS_WHEN_TOLD_ANSWERS_NOTHING]
    with up_on_a_fake_clock(cmd, problems, holds, now) as e:
        child = e._child
        assert child is not None
        asleep = reader_asleep(e)
        wait_until(asleep.is_set, 10, "the reader asleep, nothing to look at")
        asleep.clear()

        real_unread = express_module._unread
        armed = threading.Event()
        left_out: list[bool] = []

        def unread(sock: Any) -> bool:
            # the tick's own last look (not unread_for's), once: a stop carried out on another
            # thread puts its hold right then, and the child reads the vouch's word meanwhile
            if armed.is_set() and sys._getframe(1).f_code.co_name == "_tick":
                armed.clear()
                putting = threading.Thread(target=e.hold, args=("a",))
                putting.start()
                putting.join()
                outbox = e._sock
                left_out.append(outbox is not None and outbox._cover is not None)
                os.kill(child.pid, signal.SIGUSR1)
                wait_until(lambda: not real_unread(sock), 10, "the vouch's word read")
            return real_unread(sock)

        monkeypatch.setattr(express_module, "_unread", unread)
        armed.set()
        e.vouch("main", 0.0)  # a bridge connection's SUBACK: request 1, a word sent
        wait_until(asleep.is_set, 10, "the tick's verdict given")
        assert left_out == [True]  # the hold's request 2 was left out (1 unread then)
        assert ("hold", "a", 2) in holds.log
        now[0] += LONG_HOLD_S + RESEND_S  # the broker dropped the word: nothing answers it
        wait_until(
            lambda: any("not yet answered" in p for p in problems.on()),
            5,
            "the long hold said (and its word asked for again)",
        )
