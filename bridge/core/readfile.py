"""Reading a file a user named (a TLE file, a cty file): its bytes, bounded, and only if it is
a regular file; and which paths a user names are the process's own descriptors. No thread of
its own; the caller says what a refusal means to it.

Rules:
1. The file is opened without waiting and without adopting it (O_NONBLOCK: a FIFO's open waits
   for a writer that may never come; O_NOCTTY: a terminal line named here would become a
   service's controlling terminal, and its hang-up, SIGHUP, end the bridge: review 69), and
   judged by what is open, not by what a look before saw: anything but a regular file is
   ``NotRegular``, unread.
2. At most ``limit`` bytes are read: one more is ``TooLarge`` (a file that grew past the limit
   between a look at its size and the read; /dev/zero named by mistake never is, rule 1).
3. ``stream_fd``: a path that names one of the process's own descriptors by its name alone
   (``/dev/stdout``, ``/dev/stderr``, ``/dev/fd/N``, ``/proc/self/fd/N``) is that descriptor,
   whatever it is now: the audit file written there (runtime/audit.py rule 11), judged by the
   name in the settings (settings rule 6; review 87).
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path

from bridge.core.text import shown_path

_FLAGS = (
    os.O_RDONLY
    | getattr(os, "O_NONBLOCK", 0)
    | getattr(os, "O_NOCTTY", 0)
    | getattr(os, "O_CLOEXEC", 0)
    | getattr(os, "O_BINARY", 0)  # (Windows)
)


class NotRegular(OSError):
    """Rule 1: a device, a pipe, a folder."""


class TooLarge(OSError):
    """Rule 2: more than the limit."""


def read_regular(path: Path, limit: int) -> bytes:
    """The bytes of the regular file at ``path``, at most ``limit`` of them (rules 1, 2);
    NotRegular, TooLarge, or the OSError of the open or the read."""
    fd = os.open(path, _FLAGS)
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise NotRegular(f"{shown_path(path)} is no regular file")
        chunks: list[bytes] = []
        size = 0
        while size <= limit:
            chunk = os.read(fd, limit + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    finally:
        os.close(fd)
    if size > limit:
        raise TooLarge(f"{shown_path(path)} is over {limit} bytes")
    return b"".join(chunks)


# rule 3: the names of the process's own descriptors
_STREAM = re.compile(r"/dev/(?:std(out|err)|fd/([0-9]{1,9}))|/proc/self/fd/([0-9]{1,9})")


def stream_fd(path: str | os.PathLike[str]) -> int | None:
    """Rule 3: the process's own descriptor ``path`` names by its name alone (``/dev/stdout``
    1, ``/dev/stderr`` 2, ``/dev/fd/N`` and ``/proc/self/fd/N`` N), else None."""
    m = _STREAM.fullmatch(os.fspath(path))
    if m is None:
        return None
    std, fd, proc = m.groups()
    if std is not None:
        return 1 if std == "out" else 2
    return int(fd if fd is not None else proc)
