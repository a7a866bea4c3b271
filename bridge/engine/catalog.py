"""The satellites a rotator can be told to track by name: ``[tracking] tle_file``.

Rules:
1. The file is read when a name is looked up and it changed since the last read (its size or
   modification time): a cron job refreshing it needs no restart. Nothing is ever downloaded.
2. A file that cannot be read keeps the satellites last read from it, and says so once per
   change; a bad element set in it is skipped with a warning naming its line (sky.parse_tles).
3. Names are matched ignoring case and surrounding blanks; the catalog number works too.
"""

from __future__ import annotations

import logging
import os
import threading
from pathlib import Path

from bridge.sky import Body, SkyError, parse_tles

log = logging.getLogger(__name__)


class CatalogError(ValueError):
    """No such satellite, or no file: the message says which."""


class TleCatalog:
    def __init__(self, path: Path | None) -> None:
        self.path = path
        self._lock = threading.Lock()  # looked up from paho's thread and rotctld's
        self._seen: tuple[int, int] | None = None
        self._sets: dict[str, tuple[str, str, str]] = {}  # folded name -> (name, line1, line2)

    def names(self) -> list[str]:
        with self._lock:
            self._refresh()
            return sorted({name for name, _l1, _l2 in self._sets.values()})

    def lookup(self, name: str) -> Body:
        """The satellite called ``name`` (CatalogError if there is none)."""
        with self._lock:
            if self.path is None:
                raise CatalogError(
                    f"no satellite {name!r}: no tle_file is configured ([tracking] tle_file); "
                    'send the elements as {"tle": ["NAME", "1 ...", "2 ..."]}'
                )
            self._refresh()
            key = _fold(name)
            found = self._sets.get(key)  # a name first, even one of digits ("0815")
            if found is None and key.isdigit():
                found = self._sets.get(key.lstrip("0"))  # then a catalog number
            if found is None:
                count = len(set(self._sets.values()))  # each set is there by name and number
                raise CatalogError(f"no satellite {name!r} in {self.path} ({count} satellites)")
        try:
            return Body.satellite(*found)
        except SkyError as exc:  # parse_tles checked it already; a defect if it happens
            raise CatalogError(f"{name!r} in {self.path}: {exc}") from None

    def _refresh(self) -> None:
        """Rule 1 and 2 (under the lock)."""
        if self.path is None:
            return
        try:
            st = os.stat(self.path)
            seen = (st.st_size, st.st_mtime_ns)
            if seen == self._seen:
                return
            text = self.path.read_text(encoding="ascii", errors="replace")
        except OSError as exc:
            if self._seen != (-1, -1):
                log.warning("tle_file %s cannot be read: %s", self.path, exc.strerror or exc)
                self._seen = (-1, -1)
            return
        self._seen = seen
        sets, problems = parse_tles(text)
        for problem in problems:
            log.warning("tle_file %s: %s", self.path, problem)
        self._sets = {}
        for set_name, (line1, line2) in sets.items():
            entry = (set_name, line1, line2)
            self._sets[_fold(set_name)] = entry
        for entry in list(self._sets.values()):  # catalog numbers, after every name
            self._sets.setdefault(entry[1][2:7].strip().lstrip("0"), entry)
        log.info("tle_file %s: %d satellite(s)", self.path, len(sets))


def _fold(name: str) -> str:
    return name.strip().casefold()
