"""The files the console reads: its page (``static/``, read once at start, served from memory,
gzipped once) and this installation's own secret (auth.py rule 2), beside the state file."""

from __future__ import annotations

import gzip
import logging
import os
import secrets
from importlib import resources
from pathlib import Path

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


def installation_secret(path: Path) -> bytes:
    """This installation's own random secret (auth.py rule 2), made once and kept in ``path``
    (readable by the service alone). One that cannot be kept is made for this run only: tokens
    then end with it, as they do without a password."""
    try:
        data = path.read_bytes()
        if len(data) >= 32:
            return data
    except FileNotFoundError:
        pass
    except OSError as exc:
        log.warning("web console: %s cannot be read (%s): logins end at a restart", path, exc)
        return secrets.token_bytes(32)
    data = secrets.token_bytes(32)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "wb") as out:
            out.write(data)
    except OSError as exc:
        log.warning("web console: %s cannot be written (%s): logins end at a restart", path, exc)
    return data
