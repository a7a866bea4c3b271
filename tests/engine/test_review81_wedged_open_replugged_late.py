"""Review 81, runtime/worker.py rule 4 in virtual time on real pyserial and a real pty: an
adapter whose driver wedges (every open() of the old device hangs for good, as the rule
models it: "a thread stuck in the kernel cannot be ended") and that the user pulls and plugs
back in, not within the first OPEN_BOUND_S but later (the usual case: someone notices the
rotator offline after a minute).

Rule 4 gives the first hung open up after OPEN_BOUND_S and tries again at once; that second
try finds the device still wedged and hangs too. From then on it is "waited for, looked at
again every OPEN_BOUND_S, not abandoned" while the first is still inside its open(), which it
is for good. So the replugged adapter (its stable name now on a new device, which opens at
once) is never tried: the rotator stays offline, every target refused and every STOP only
owed, until the bridge is restarted: attack 23's symptom, for a replug later than 10 s.
"""

from __future__ import annotations

import os
import select
import threading
from functools import partial
from pathlib import Path

import serial

from bridge.app import worker_config
from bridge.protocols.base import ModelSpec
from bridge.runtime.port import PendingOpen, open_port
from bridge.runtime.worker import OPEN_BOUND_S, Worker
from bridge.session.mailbox import Mailbox
from bridge.settings import RotatorSettings
from tests.support import wait_until
from tests.support.rig import FAST_BRIDGE
from tests.support.waiting import slow

START = 100.0
REPLUGGED_AFTER_S = 60.0  # the user pulls and replugs the adapter a minute after it wedged
BACK_WITHIN_S = 3 * OPEN_BOUND_S  # generous: a hung try given up, another, and one more


def has_result(opening: PendingOpen) -> bool:
    return opening.result is not None


class WedgedUntilReplugged:
    """open() of the old device hangs for good (released only when the test ends); once the
    adapter is replugged, an open() opens the new device (the pty) at once."""

    def __init__(self, tty: str) -> None:
        self.tty = tty
        self.replugged = threading.Event()
        self.gate = threading.Event()  # the test's end: the stuck threads let go
        self.hung = 0
        self.after_replug = 0

    def __call__(self, path: str, spec: ModelSpec, baud: int | None) -> serial.Serial:
        if not self.replugged.is_set():
            self.hung += 1
            self.gate.wait(slow(120))  # a guard, past the test's end (not a deadline it judges)
            raise serial.SerialException("the wedged open let go")
        self.after_replug += 1
        return open_port(self.tty, spec, baud)


def test_an_adapter_replugged_a_minute_after_it_wedged_comes_back(tmp_path: Path) -> None:
    master, slave = os.openpty()
    opener = WedgedUntilReplugged(os.ttyname(slave))
    settings = RotatorSettings.model_validate(
        {"id": "tower", "model": "rotorez", "port": str(tmp_path / "by-id"), **FAST_BRIDGE}
    )
    box = Mailbox()
    worker = Worker(
        worker_config(settings), box, lambda s: None, lambda e: None, port_opener=opener
    )

    def served(now: float) -> float:
        worker.guarded(worker.serve, now, set())
        return worker.wants(now)[1]

    try:
        worker.guarded(worker.begin, START, lambda: None)
        now = served(START)
        wait_until(lambda: opener.hung == 1, slow(5), "the first open() hanging")
        first = worker._opening
        while worker._opening is first:  # served at each time asked for, up to the bound
            now = served(now)
        served(now)  # given up at the bound, and tried again at once
        wait_until(lambda: opener.hung == 2, slow(5), "the second open() hanging")
        replug_t = START + REPLUGGED_AFTER_S
        while now < replug_t:  # the adapter still wedged: the worker serves on its own times
            now = max(served(now), now + OPEN_BOUND_S / 4)
        opener.replugged.set()  # the user pulls the adapter and plugs it back in
        now = replug_t
        while now <= replug_t + BACK_WITHIN_S and not opener.after_replug:
            now = max(served(now), now + OPEN_BOUND_S / 4)
        opening = worker._opening
        if opener.after_replug and opening is not None:
            wait_until(partial(has_result, opening), slow(5), "the new device's open() back")
            served(now)
        assert opener.after_replug, (
            f"the adapter replugged {REPLUGGED_AFTER_S:g} s after it wedged was not tried "
            f"within {BACK_WITHIN_S:g} s (virtual): {opener.hung} open()s hanging on the old "
            f"device, none on the new one"
        )
        assert select.select([master], [], [], slow(5))[0]
        assert b"AI1;" in os.read(master, 64)  # the controller asked its bearing again
    finally:
        opener.gate.set()
        worker.guarded(worker.end, START)
        assert worker.wait_closed(slow(5))
        box.close()
        os.close(master)
        os.close(slave)
