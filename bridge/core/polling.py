"""Waiting on descriptors with ``poll()`` where the system has it, and with the same calls made
of ``select()`` where it has not: Windows, where the remote runs on an operator's computer
(docs/deployment.md).

Rules:
1. ``new_poller()`` is ``select.poll()`` on every POSIX system: the bridge's threads wait there
   (``select()`` refuses a descriptor numbered 1024 or more, and a busy bridge gets there).
   Where ``select`` has no ``poll``, it is a ``SelectPoller``: ``register``, ``modify``,
   ``unregister`` and ``poll(ms)`` as ``poll()``'s, over ``select.select`` (Windows' takes a
   socket whatever its number; the remote waits on a few).
2. The event bits are ``select``'s where it has them, Linux's values where it has not, so that
   a caller reads the same names either way.
3. A ``SelectPoller`` whose ``select`` refuses its descriptors (one was closed under it) says
   ``POLLNVAL`` for every one, as ``poll()`` says it for a closed one: the caller sees its
   socket gone and makes it again.
"""

from __future__ import annotations

import select
import threading
from typing import Protocol

__all__ = [
    "POLLERR",
    "POLLHUP",
    "POLLIN",
    "POLLNVAL",
    "POLLOUT",
    "POLLPRI",
    "Poller",
    "SelectPoller",
    "new_poller",
]

# rule 2
POLLIN: int = getattr(select, "POLLIN", 0x001)
POLLPRI: int = getattr(select, "POLLPRI", 0x002)
POLLOUT: int = getattr(select, "POLLOUT", 0x004)
POLLERR: int = getattr(select, "POLLERR", 0x008)
POLLHUP: int = getattr(select, "POLLHUP", 0x010)
POLLNVAL: int = getattr(select, "POLLNVAL", 0x020)


class _HasFileno(Protocol):
    def fileno(self) -> int: ...


class Poller(Protocol):
    """What the bridge asks of ``select.poll()`` (rule 1)."""

    def register(self, fd: int | _HasFileno, eventmask: int = ..., /) -> None: ...
    def modify(self, fd: int | _HasFileno, eventmask: int, /) -> None: ...
    def unregister(self, fd: int | _HasFileno, /) -> None: ...
    def poll(self, timeout: float | None = ..., /) -> list[tuple[int, int]]: ...


def _fileno(fd: int | _HasFileno) -> int:
    return fd if isinstance(fd, int) else fd.fileno()


class SelectPoller:
    """``poll()``'s calls over ``select.select`` (rules 1 and 3)."""

    def __init__(self) -> None:
        self._masks: dict[int, int] = {}

    def register(self, fd: int | _HasFileno, eventmask: int = POLLIN | POLLPRI | POLLOUT) -> None:
        self._masks[_fileno(fd)] = eventmask

    def modify(self, fd: int | _HasFileno, eventmask: int) -> None:
        number = _fileno(fd)
        if number not in self._masks:
            raise FileNotFoundError(f"descriptor {number} is not registered")
        self._masks[number] = eventmask

    def unregister(self, fd: int | _HasFileno) -> None:
        del self._masks[_fileno(fd)]  # KeyError for one not registered, as poll()'s

    def poll(self, timeout: float | None = None) -> list[tuple[int, int]]:
        """``timeout`` in milliseconds; None or a negative one: no limit."""
        wait_s = None if timeout is None or timeout < 0 else timeout / 1000
        reads = [fd for fd, mask in self._masks.items() if mask & (POLLIN | POLLPRI)]
        writes = [fd for fd, mask in self._masks.items() if mask & POLLOUT]
        if not reads and not writes:  # select() with nothing to wait on refuses on Windows
            threading.Event().wait(wait_s)
            return []
        try:
            readable, writable, odd = select.select(reads, writes, reads, wait_s)
        except (OSError, ValueError):  # rule 3
            return [(fd, POLLNVAL) for fd in self._masks]
        ready: dict[int, int] = {}
        for fd in readable:
            ready[fd] = ready.get(fd, 0) | POLLIN
        for fd in odd:
            ready[fd] = ready.get(fd, 0) | POLLPRI
        for fd in writable:
            ready[fd] = ready.get(fd, 0) | POLLOUT
        return list(ready.items())


def new_poller() -> Poller:
    """Rule 1."""
    poll = getattr(select, "poll", None)
    return SelectPoller() if poll is None else poll()
