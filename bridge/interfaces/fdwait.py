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
3. ``ready_held`` asks the same of many descriptors at once without waiting, and keeps the
   interpreter lock meanwhile (ctypes' PyDLL: one ``poll`` of a tenth of a millisecond or so in
   the kernel, and no other thread takes the lock, then keeps it for up to its switch interval,
   5 ms, before the caller has it back); on Linux alone (elsewhere ``readable``'s, which lets
   it go). For a look right before a halt (interfaces/web/looks.py rule 4).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Sequence
from typing import Any

from bridge.core.polling import POLLIN, POLLOUT, POLLPRI, new_poller

__all__ = ["libc_holding", "readable", "ready_held", "writable"]

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


def libc_holding(name: str, *argtypes: Any) -> Any | None:
    """Rule 3: libc's ``name`` called through ctypes' PyDLL, which keeps the interpreter lock
    across the call, taking ``argtypes`` and returning an int (errno kept for
    ``ctypes.get_errno``); None off Linux, or where it cannot be had (the caller then asks
    the way that lets the lock go)."""
    if sys.platform != "linux":
        return None
    try:
        import ctypes

        call = ctypes.PyDLL(None, use_errno=True)[name]
    except (ImportError, OSError, AttributeError):
        return None
    call.argtypes = argtypes
    call.restype = ctypes.c_int
    return call


def _polling_holding() -> Callable[[list[int]], set[int]]:
    """Rule 3. Its ``struct pollfd`` array is an ``array`` of int pairs (a descriptor; its
    events, the kernel's answer beside them in the same four bytes)."""

    def letting_go(fds: list[int]) -> set[int]:
        return set(readable(fds, 0))

    try:
        import array
        import ctypes
    except ImportError:
        return letting_go
    poll = libc_holding("poll", ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int)
    if poll is None or array.array("i").itemsize != 4 or ctypes.sizeof(ctypes.c_short) != 2:
        return letting_go
    asked = POLLIN | POLLPRI
    shift = 16 if sys.byteorder == "little" else 0  # (where revents sits in the second int)

    def held(fds: list[int]) -> set[int]:
        pairs = array.array("i", [asked << (16 - shift)]) * (2 * len(fds))
        pairs[0::2] = array.array("i", fds)  # (a negative one: never ready, rule 2)
        if fds and poll(pairs.buffer_info()[0], len(fds), 0) < 0:
            return letting_go(fds)  # (EINTR, ENOMEM: asked again, the lock let go)
        return {fd for fd, word in zip(fds, pairs[1::2], strict=True) if (word >> shift) & 0xFFFF}

    return held


ready_held = _polling_holding()
