"""Review 84 (15deeb17: worker.py rule 4, ``_device_node``): while abandoned opens still hang,
the port's path is looked at every NODE_LOOK_S, and a device node that changed from the one the
pending attempt started on is taken for a replug: that attempt is abandoned too (its thread left
hanging in the kernel) and the port tried again at once. "Changed" includes ``st_ctime``, which
moves with no replug at all: a chmod or chown of the node, an ACL set on it, udev re-applying a
rule's permissions at a ``change`` event (``udevadm trigger`` after a package install) or
touching the node's times. Each such touch of a wedged adapter's node is said on R/error as "is
another device now (replugged?)", and leaves one more thread stuck in open() on the same wedged
device: the threads grow with the touches, not with the log of the time as rule 4 promises
(observed: five touches, four attempts in open() on the one wedged device, none replugged)."""

from __future__ import annotations

import os
from pathlib import Path

from bridge.app import worker_config
from bridge.runtime.worker import NODE_LOOK_S, Worker
from bridge.session.mailbox import Mailbox
from bridge.settings import RotatorSettings
from tests.engine.test_worker_reopen import START, WedgedOn
from tests.support import wait_until
from tests.support.rig import FAST_BRIDGE
from tests.support.waiting import slow

TOUCHES = 5  # the node's permissions set again, NODE_LOOK_S apart: no replug


def test_the_wedged_device_node_touched_in_place_is_no_replug(tmp_path: Path) -> None:
    link = tmp_path / "by-id-tower"  # the adapter's stable name
    old_master, old_slave = os.openpty()
    tty = os.ttyname(old_slave)
    link.symlink_to(tty)  # the wedged adapter, never replugged in this test
    opener = WedgedOn(tty)
    settings = RotatorSettings.model_validate(
        {"id": "tower", "model": "rotorez", "port": str(link), **FAST_BRIDGE}
    )
    box, events = Mailbox(), []
    worker = Worker(worker_config(settings), box, lambda s: None, events.append, port_opener=opener)

    def served(now: float) -> float:
        worker.guarded(worker.serve, now, set())
        return worker.wants(now)[1]

    mode = os.stat(tty).st_mode & 0o7777
    try:
        worker.guarded(worker.begin, START, lambda: None)
        now = served(START)
        wait_until(lambda: opener.hung == 1, slow(5), "the first open() hanging")
        first = worker._opening
        while worker._opening is first:  # served at each time asked for, up to the bound
            now = served(now)
        served(now)  # given up at the bound, and tried again at once
        wait_until(lambda: opener.hung == 2, slow(5), "the second open() hanging")
        second = worker._opening
        for _ in range(TOUCHES):
            touched = os.stat(tty).st_ctime_ns

            def chmod_again(was: int = touched) -> bool:
                os.chmod(tty, mode)  # the same permissions set again: only its ctime moves
                return os.stat(tty).st_ctime_ns != was  # (the kernel's clock tick passed)

            wait_until(chmod_again, slow(5), "the node's ctime moved")
            end = now + NODE_LOOK_S
            while now < end:  # served at each time the worker asks for, NODE_LOOK_S on
                now = served(now)
            served(now)
        assert not [e for e in events if "another device now" in e.message]  # no replug
        assert worker._opening is second  # the same device: still waited for
        assert opener.hung == 2  # no thread more stuck in the wedged driver
    finally:
        opener.gate.set()
        worker.guarded(worker.end, START)
        assert worker.wait_closed(slow(5))
        box.close()
        for fd in (old_master, old_slave):
            os.close(fd)
