"""The files the console reads: its page (``static/``, read once at start, served from memory,
gzipped once) and this installation's own secret (auth.py rule 2), beside the state file.

Rules:
1. The secret's file is opened without waiting and read only if it is a regular file, at most
   SECRET_READ_MAX bytes: anything else there (a FIFO, whose opening waited for ever for a
   writer; a link to ``/dev/zero``, read until the memory ran out) is said and the secret is
   this run's own, as for a file that cannot be read. An attack pass: a FIFO at
   ``console-secret`` held the start for ever, without a word. What it is is looked at before
   it is opened (a review: a link to a serial port was opened, and its DTR raised).
"""

from __future__ import annotations

import errno
import gzip
import logging
import os
import secrets
import stat
from importlib import resources
from pathlib import Path

from bridge.core.text import shown_path

log = logging.getLogger(__name__)

_TYPES = {
    ".html": "text/html",
    ".js": "text/javascript",
    ".css": "text/css",
    ".svg": "image/svg+xml",
}


def static_files() -> dict[str, tuple[bytes, bytes, str]]:
    """The page's files: name -> (bytes, gzipped, content type)."""
    files = {}
    folder = resources.files("bridge.interfaces.web").joinpath("static")
    if folder.is_dir():
        for item in folder.iterdir():
            kind = _TYPES.get("." + item.name.rpartition(".")[2])
            if item.is_file() and kind is not None:
                data = item.read_bytes()
                files[item.name] = (data, gzip.compress(data, mtime=0), f"{kind}; charset=utf-8")
    return files


SECRET_READ_MAX = 4096  # rule 1: the most of the secret's file read (the bridge writes 32)


def _read_secret(path: Path) -> bytes:
    """Rule 1: the file's first bytes; FileNotFoundError if there is none, OSError for what is
    no regular file (looked at before it is opened: opening a link to a serial port raises its
    DTR, which resets some controllers)."""
    if not stat.S_ISREG(os.stat(path).st_mode):
        raise OSError(errno.EINVAL, "not a regular file")
    flags = os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC | getattr(os, "O_NOCTTY", 0)
    fd = os.open(path, flags)
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(errno.EINVAL, "not a regular file")
        return os.read(fd, SECRET_READ_MAX)
    finally:
        os.close(fd)


def installation_secret(path: Path) -> bytes:
    """This installation's own random secret (auth.py rule 2), made once and kept in ``path``
    (readable by the service alone). One that cannot be kept is made for this run only: tokens
    then end with it, as they do without a password."""
    try:
        data = _read_secret(path)  # rule 1
        if len(data) >= 32:
            return data
    except FileNotFoundError:
        pass
    except OSError as exc:
        log.warning(
            "web console: %s cannot be read (%s): logins end at a restart",
            shown_path(path),
            shown_path(str(exc)),
        )
        return secrets.token_bytes(32)
    data = secrets.token_bytes(32)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "wb") as out:
            out.write(data)
    except OSError as exc:
        log.warning(
            "web console: %s cannot be written (%s): logins end at a restart",
            shown_path(path),
            shown_path(str(exc)),
        )
    return data
