"""Waiting on raw descriptors (a pty, a wake pipe, a socket) with ``poll()``.

``select()`` refuses a descriptor numbered 1024 or more, and a busy bridge's process gets there
(every client, port, pipe and log file is one): a thread that waited in ``select()`` then ended
at its first wait with ValueError, and what it served went silent (a pty's client, the loggers'
loop, the stop lane's yield). Selectors (``selectors.DefaultSelector``: epoll) have no such
limit and stay where they are used.

Rules:
1. Every wait of interfaces/ on a raw descriptor goes through here; none calls ``select()``
   (tests/test_house.py looks).
2. A timeout is in seconds, None for no limit; a descriptor that reports an error or a hang-up
   (or was closed since it was handed over) counts as ready, as ``select()`` had it: the read or
   write that follows says what happened. A descriptor numbered -1 (a socket already closed) is
   not waited on and never ready (``select()`` raised ValueError for it): a wait with no other
   descriptor is its timeout alone, and for ever with None.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from bridge.core.polling import POLLIN, POLLOUT, POLLPRI, new_poller

__all__ = ["readable", "writable"]

_IN = POLLIN | POLLPRI
_OUT = POLLOUT


def _wait(fds: Sequence[int], mask: int, timeout_s: float | None) -> list[int]:
    poller = new_poller()  # poll(); on Windows (the remote) one made of select()
    for fd in fds:
        if fd >= 0:
            poller.register(fd, mask)
    ms = -1 if timeout_s is None else max(0, math.ceil(timeout_s * 1000))
    return [fd for fd, _events in poller.poll(ms)]


def readable(fds: Sequence[int], timeout_s: float | None) -> list[int]:
    """Those of ``fds`` with bytes to read (or an error, a hang-up: rule 2), waiting up to
    ``timeout_s`` for one."""
    return _wait(fds, _IN, timeout_s)


def writable(fd: int, timeout_s: float | None) -> bool:
    """Whether ``fd`` takes bytes (or reports an error, a hang-up: rule 2) within
    ``timeout_s``."""
    return bool(_wait((fd,), _OUT, timeout_s))
