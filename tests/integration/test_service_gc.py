"""The service's garbage collector (docs/architecture.md rule 12): what the start-up built is
frozen once everything runs, so a full collection no longer walks it beside a stop (one walk of
a started bridge's objects holds the GIL for tens of milliseconds); the freeze ends with the
service, so a process that runs the bridge again keeps no garbage."""

from __future__ import annotations

import gc
import threading

from bridge.app import run
from tests.support import wait_until
from tests.support.rig import Rig
from tests.support.waiting import slow


def test_the_running_service_has_its_start_up_frozen_and_thaws_it_at_the_end(rig: Rig) -> None:
    rig.add("tower", "rotorez")
    done = threading.Event()
    result: list[int] = []
    thread = threading.Thread(target=lambda: result.append(run(rig.settings, done)))
    before = gc.get_freeze_count()
    thread.start()
    try:
        rig.ready("tower")
        wait_until(lambda: gc.get_freeze_count() > before + 10_000, 20, "start-up frozen")
    finally:
        done.set()
        thread.join(slow(20))
    assert result == [0]
    assert gc.get_freeze_count() == 0
