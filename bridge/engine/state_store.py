"""What must survive a restart of the bridge: each rotator's safety lock and the options the
user set (the controller forgets them at power-off, so the bridge re-applies them).

A small JSON file, replaced atomically on every change. A missing file means "nothing set";
an unreadable one is reported and treated as empty, except that every rotator whose lock state
cannot be read starts locked (safety before convenience) and is written down as locked, so it
stays locked across restarts until someone unlocks it. A malformed entry (not a table, a lock
that is not true or false, options that are not switches) does the same for its rotator alone,
and the rotator's status says why (``problems``).
"""

from __future__ import annotations

import json
import logging
import os
import tempfile
import threading
from pathlib import Path

log = logging.getLogger(__name__)


class StateStore:
    def __init__(self, path: Path | None) -> None:
        self._path = path
        self._lock = threading.Lock()
        self._data: dict[str, dict[str, object]] = {}
        self.corrupt = False
        self.problems: dict[str, str] = {}  # rotator id -> what was wrong with its entry
        self._dirty = False  # a malformed entry was replaced: written down at the first read
        if path is not None and path.exists():
            try:
                loaded = json.loads(path.read_text())
                if not isinstance(loaded, dict) or not isinstance(loaded.get("rotators"), dict):
                    raise ValueError("no 'rotators' table")
                self._data = {
                    str(k): self._entry(path, str(k), v) for k, v in loaded["rotators"].items()
                }
            except (OSError, ValueError) as exc:
                log.error("state file %s unreadable (%s): every rotator starts locked", path, exc)
                self.corrupt = True

    def _entry(self, path: Path, rotator_id: str, entry: object) -> dict[str, object]:
        """One rotator's entry as it must be; one that is not starts that rotator locked."""
        options = entry.get("options", {}) if isinstance(entry, dict) else None
        fine = (
            isinstance(entry, dict)
            and isinstance(entry.get("locked", False), bool)
            and isinstance(options, dict)
            and all(isinstance(v, bool) for v in options.values())
        )
        if fine:
            assert isinstance(entry, dict)
            return entry
        shown = json.dumps(entry)[:80]
        problem = f"state file {path}: entry for {rotator_id!r} is malformed ({shown}): locked"
        log.error("%s", problem)
        self.problems[rotator_id] = problem
        self._dirty = True
        return {"locked": True}

    def check_writable(self) -> None:
        """OSError if the file cannot be written where it is configured. Checked at start: a
        lock set for tower work that is silently not kept would be gone after a restart."""
        if self._path is None:
            return
        self._path.parent.mkdir(parents=True, exist_ok=True)
        if self._path.is_dir():
            raise IsADirectoryError(21, "a directory is in the way", str(self._path))
        fd, tmp = tempfile.mkstemp(dir=self._path.parent, prefix=".state-")
        os.close(fd)
        os.unlink(tmp)

    def locked(self, rotator_id: str) -> bool:
        with self._lock:
            if self._dirty:  # the replacement of a malformed entry, locked, kept for next time
                self._dirty = False
                self._save()
            entry = self._data.get(rotator_id, {})
            if self.corrupt and "locked" not in entry:
                # written down explicitly, so the next start is locked too until someone unlocks
                self._data.setdefault(rotator_id, {})["locked"] = True
                self._save()
                return True
            return bool(entry.get("locked", False))

    def options(self, rotator_id: str) -> dict[str, bool]:
        raw = self._data.get(rotator_id, {}).get("options", {})
        if not isinstance(raw, dict):
            return {}
        return {str(k): bool(v) for k, v in raw.items()}

    def set_locked(self, rotator_id: str, locked: bool) -> bool:
        """Remember the lock; False if it could not be written (it will not survive a restart)."""
        with self._lock:
            self._data.setdefault(rotator_id, {})["locked"] = locked
            return self._save()

    def set_option(self, rotator_id: str, name: str, enabled: bool) -> bool:
        with self._lock:
            entry = self._data.setdefault(rotator_id, {})
            opts = entry.setdefault("options", {})
            assert isinstance(opts, dict)
            opts[name] = enabled
            return self._save()

    def _save(self) -> bool:
        if self._path is None:
            return True
        try:
            self._path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=self._path.parent, prefix=".state-")
            with os.fdopen(fd, "w") as f:
                json.dump({"rotators": self._data}, f, indent=1, sort_keys=True)
            os.replace(tmp, self._path)
            return True
        except OSError as exc:
            log.error("cannot write state file %s: %s", self._path, exc)
            return False
