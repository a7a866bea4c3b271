"""Which of the bridge's threads a busy machine runs first: the stop's path before everything
else (docs/architecture.md, "Threads and queues").

The interpreter lock is shared by every thread, but it is handed over within the switch
interval (app.py's GIL_SWITCH_S) to a thread that asks for it. A thread can only ask when the
kernel gives it a core, though, and on a machine with more runnable threads than cores a
thread can wait tens of milliseconds for one. So the stop's path must not compete for a core
on equal terms with a backlog, a flood or a page:

Rules:
1. The stop's path keeps the process's priority: the stop lane's network thread (it takes a
   STOP off the broker and decides it), the serial-lines thread (it writes it to the
   controller), and the main thread.
2. Every other long-lived thread of the bridge (the main connection's network thread, the
   TCP, pty and UDP front ends, the DX cluster client, the console's web server, the sky
   worker, the state writer, the audit) calls ``background()`` first thing: the kernel then
   runs it only when the stop's path has no use for a core (a nice value BACKGROUND_NICE above
   the process's). Linux keeps a nice value per thread, and a thread started by a background
   thread inherits it (a TCP client's thread, started by its listener's).
3. Lowering a priority needs no privilege. Where the kernel refuses anyway (not Linux, a
   sandbox that forbids it), the thread runs as before and one debug line says so: priority is
   a help to the stop's latency, never a condition of its correctness (a background thread
   still gets all the CPU the stop's path leaves).
"""

from __future__ import annotations

import logging
import os
import sys
import threading
from collections.abc import Callable

log = logging.getLogger(__name__)

BACKGROUND_NICE = 10  # rule 2: CFS gives a nice-0 thread ~10 times the share of a nice-10 one

_refused = False  # rule 3: said once


def background() -> None:
    """Rule 2: lower the calling thread's scheduling priority (idempotent per thread: a thread
    already at or below the background level stays where it is)."""
    global _refused
    if not sys.platform.startswith("linux"):
        return
    tid = threading.get_native_id()
    try:
        base = os.getpriority(os.PRIO_PROCESS, os.getpid())  # the main thread's: rule 1's level
        if os.getpriority(os.PRIO_PROCESS, tid) >= base + BACKGROUND_NICE:
            return
        os.setpriority(os.PRIO_PROCESS, tid, min(base + BACKGROUND_NICE, 19))
    except OSError as exc:
        if not _refused:
            _refused = True
            log.debug("thread priorities not lowered (%s): every thread runs at one priority", exc)


def background_thread(target: Callable[[], object], name: str) -> threading.Thread:
    """Rule 2: a daemon thread that lowers its own priority, then runs ``target``."""

    def run() -> None:
        background()
        target()

    return threading.Thread(target=run, name=name, daemon=True)
