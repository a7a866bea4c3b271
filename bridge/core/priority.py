"""Which of the bridge's threads give way when the host has more runnable threads than cores:
the kernel's scheduling priority (a nice value) of each front-end thread.

A stop is carried by a few threads and one process (the stop's path): the main thread, the
serial-lines thread and the short-lived threads it starts to open and close ports, the stop
lane's paho thread, the stop express's reader and the express process it starts. Everything
else that reads what others send, or computes, is front-end work: the main connection's paho
thread (every message parsed), the TCP and pty line servers, the loggers' and WSJT-X's UDP
threads, the DX cluster's, the console's event loop, the sky worker, the state and audit
writers, the TLE file watcher. On a 2-core host those keep cores busy (a backlog of targets, a
flood of clients), and a stop's thread or process that wakes then waits in the kernel's run
queue behind them. Lowered, they take a core only when the stop's path (and the broker, and the
kernel's pty worker, which carry a stop too) leaves one.

Rules:
1. ``lower()`` lowers the calling thread to FRONT_NICE below the process's own priority
   (``os.setpriority`` on the thread's own id: on Linux a nice value is a thread's), never
   raises a thread's priority (one already lower keeps its own), and is idempotent. A
   front-end thread is started on ``lowered(run)``, which calls it first thing (``run`` itself
   stays callable on another thread without lowering it); ``lower(native_id)`` lowers another
   thread of the process (the main connection's, rule 3).
2. A thread starts with the nice value of the thread that starts it (a process too), and an
   unprivileged process can never raise it back. So no thread or process of the stop's path is
   ever started by a lowered thread: they are started by the main thread or by each other, and
   a lowered thread starts only front-end work (its clients, its executor, its timers).
3. The one exception by construction: the main connection's paho thread starts the stop lane
   and the stop express (app.py, once the broker took the bridge). It runs at the process's
   priority until both are started, and is lowered from then on, by the code that started them
   (before that it has done the first look, no backlog). What it starts after that (a look's
   timer, a hand-off) is front-end work and runs lowered.
4. Only the service lowers (``enable``, called by app.py before it starts anything), and only
   when the stop express (interfaces/mqtt/express.py, a process of its own) writes the first
   stop frame of every one of its rotators. A stop carried inside the bridge (a SPID's, a
   SatEL's, an RC2800's, a rotator of two boxes, all with the express off) needs this
   process's interpreter lock on the stop lane's thread and the serial-lines thread; a lowered
   thread that holds that lock is the first the kernel preempts for another program, and the
   stop would wait for it to be scheduled again (a priority inversion, measured when an earlier
   tree lowered its front ends without the express). The remote (bridge/remote) runs the same
   rotctld server and console, and there they carry the operator's stop, beside nothing
   busier of its own; it never lowers.
5. The stop express's process raises itself (``raise_express``, first thing, before it starts
   a thread: they inherit it) EXPRESS_RAISE steps above the priority it was started with,
   where the system lets it: as root, with CAP_SYS_NICE, or under a nice limit that allows it
   (the systemd unit's ``LimitNICE``). A process of its own, it holds no lock any thread of the
   bridge waits for, so raising it makes nothing wait behind it but other programs; where it
   may not, it keeps the priority it has, said once at debug level.
6. Where the system has no per-thread priority (``os.setpriority`` or
   ``threading.get_native_id`` missing: Windows) or refuses it (a sandbox), nothing changes
   and it is said once, at debug level.
"""

from __future__ import annotations

import logging
import os
import threading
from collections.abc import Callable

__all__ = ["EXPRESS_RAISE", "FRONT_NICE", "enable", "lower", "lowered", "nice_of", "raise_express"]

log = logging.getLogger(__name__)

FRONT_NICE = 10  # rule 1: how far below the process's priority front-end work runs
EXPRESS_RAISE = 10  # rule 5: how far above its starter's priority the stop express runs
MIN_NICE = -20  # the highest priority there is
MAX_NICE = 19  # the lowest priority there is

_setpriority = getattr(os, "setpriority", None)
_getpriority = getattr(os, "getpriority", None)
_PRIO_PROCESS: int | None = getattr(os, "PRIO_PROCESS", None)
_said = False  # rule 6: once
_enabled = False  # rule 4


def _nice(native_id: int) -> int | None:
    if _getpriority is None or _PRIO_PROCESS is None:
        return None
    try:
        return int(_getpriority(_PRIO_PROCESS, native_id))
    except OSError:
        return None


# rule 1: the process's own priority, as the thread that imports this (the main thread) has it
_BASE = _nice(threading.get_native_id()) if hasattr(threading, "get_native_id") else None


def nice_of(native_id: int) -> int | None:
    """A thread's nice value (None where the system has none: rule 6)."""
    return _nice(native_id)


def enable() -> None:
    """Rule 4: ``lower`` lowers from now on, in this process (the service's)."""
    global _enabled
    _enabled = True


def lower(native_id: int | None = None) -> None:
    """Rule 1: the calling thread (or ``native_id``, a thread of this process) at FRONT_NICE
    below the process; never raised, never raises."""
    if not _enabled:
        return
    if _setpriority is None or _PRIO_PROCESS is None or _BASE is None:
        _say("this system has no per-thread priority")
        return
    tid = threading.get_native_id() if native_id is None else native_id
    target = min(MAX_NICE, _BASE + FRONT_NICE)
    now = _nice(tid)
    if now is not None and now >= target:
        return  # already as low (rule 1: never raised)
    try:
        _setpriority(_PRIO_PROCESS, tid, target)
    except OSError as exc:
        _say(f"cannot lower a thread's priority: {exc}")


def lowered(run: Callable[[], None]) -> Callable[[], None]:
    """Rule 1 as a thread's target: ``run`` on a thread lowered first (the thread's code stays
    callable on any other thread, a test's, without lowering that one)."""

    def _lowered() -> None:
        lower()
        run()

    return _lowered


def _say(why: str) -> None:
    global _said
    if not _said:
        _said = True
        log.debug("front-end threads run at the process's priority: %s", why)


def raise_express() -> int | None:
    """Rule 5: this process (the stop express, before any thread of its own) EXPRESS_RAISE
    above the priority it started with, where the system allows it; its nice value after."""
    if _setpriority is None or _PRIO_PROCESS is None or not hasattr(threading, "get_native_id"):
        return None
    tid = threading.get_native_id()
    now = _nice(tid)
    if now is None:
        return None
    try:
        _setpriority(_PRIO_PROCESS, tid, max(MIN_NICE, now - EXPRESS_RAISE))
    except OSError as exc:  # EACCES/EPERM: no privilege, or above the nice limit
        log.debug("the stop express runs at its starter's priority: %s", exc)
    return _nice(tid)
