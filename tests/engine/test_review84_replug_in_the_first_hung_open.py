"""Review 84 (15deeb17: worker.py rule 4, NODE_LOOK_S): a replug is seen on the port's path
within NODE_LOOK_S only "while abandoned attempts still hang"; the first attempt that hangs is
waited for its whole OPEN_BOUND_S (10 s) with the path never looked at. That is the common
case: the adapter wedges mid-turn, the operator presses STOP (owed: the port is out), sees the
rotor go on and pulls the adapter and plugs it back in at once. The new device sits on the
stable name unused, and the owed STOP reaches it only when the first hung open's bound is over,
some 9 s after the replug, while the rotor turns on (50 degrees at 6 deg/s)."""

from __future__ import annotations

import os
import select
from functools import partial
from pathlib import Path

from bridge.app import worker_config
from bridge.core.model import Stop
from bridge.runtime.worker import NODE_LOOK_S, OPEN_BOUND_S, OWED_RETRY_S, Worker
from bridge.session.mailbox import Mailbox
from bridge.settings import RotatorSettings
from tests.engine.test_worker_reopen import START, WedgedOn, has_result
from tests.support import wait_until
from tests.support.rig import FAST_BRIDGE
from tests.support.waiting import slow


def test_a_replug_during_the_first_hung_open_has_the_owed_stop_out_promptly(
    tmp_path: Path,
) -> None:
    link = tmp_path / "by-id-tower"  # the adapter's stable name
    old_master, old_slave = os.openpty()
    master, slave = os.openpty()
    link.symlink_to(os.ttyname(old_slave))  # the adapter, its driver wedged
    opener = WedgedOn(os.ttyname(old_slave))
    settings = RotatorSettings.model_validate(
        {"id": "tower", "model": "rotorez", "port": str(link), **FAST_BRIDGE}
    )
    box, events = Mailbox(), []
    worker = Worker(worker_config(settings), box, lambda s: None, events.append, port_opener=opener)

    def served(now: float, ready: frozenset[int] = frozenset()) -> float:
        worker.guarded(worker.serve, now, set(ready))
        return worker.wants(now)[1]

    try:
        worker.guarded(worker.begin, START, lambda: None)
        served(START)
        wait_until(lambda: opener.hung == 1, slow(5), "the first open() hanging")
        first = worker._opening
        pressed = START + 0.5
        box.put(Stop())  # the operator's STOP, the port out: owed
        now = served(pressed, frozenset({box.fileno()}))
        assert worker.status.stop_owed
        replug_t = START + 1.0  # pulled and plugged back in: a new device on the stable name
        link.unlink()
        link.symlink_to(os.ttyname(slave))
        now = max(now, replug_t)
        while worker._opening is first:  # served at each time the worker asks for
            now = served(now)
        # observed: given up at START + OPEN_BOUND_S, 9 s after the replug
        assert now - replug_t <= NODE_LOOK_S + OWED_RETRY_S, (replug_t, now, OPEN_BOUND_S)
        served(now)
        opening = worker._opening
        assert opening is not None
        wait_until(partial(has_result, opening), slow(5), "the new device's open() back")
        served(now)
        assert select.select([master], [], [], slow(5))[0]
        assert os.read(master, 64).startswith(b";")  # the owed stop is the first frame
    finally:
        opener.gate.set()
        worker.guarded(worker.end, START)
        assert worker.wait_closed(slow(5))
        box.close()
        for fd in (old_master, old_slave, master, slave):
            os.close(fd)
