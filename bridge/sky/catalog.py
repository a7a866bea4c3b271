"""The satellites a rotator can be told to track by name: ``[tracking] tle_file``.

Rules:
1. The file is read when a name is looked up and it changed since the last read (its size or
   modification time): a cron job refreshing it needs no restart. Nothing is ever downloaded.
   Reading and parsing are slow (a large file takes seconds): lookups run on the sky worker
   (skywork.py) and the names for Home Assistant on the app's own thread, never on paho's or
   the serial lines' thread (docs/architecture.md rule 12). Only ``check_configured`` is instant.
2. A file that cannot be read keeps the satellites last read from it, and says so once per
   change; bad element sets in it are skipped with one warning per read, counting them and
   naming the first (sky.parse_tles).
3. Names are matched ignoring case and surrounding blanks; the catalog number works too.
4. A file larger than MAX_FILE_BYTES is not read (a TLE file of every active satellite is
   about 2 MB): it counts as a file that cannot be read, and a lookup is refused naming the
   file and the limit. So is what is no regular file (a device, a pipe), its kind seen on the
   file opened without waiting, before a byte is read (attack 18: ``/dev/zero``, of size 0,
   was read to the limit at every change of nothing; a FIFO nobody writes held the catalog's
   lock, and every lookup behind it, for ever). A file that grew past the limit between its
   size and its read is not read either: its first 4 MiB are no TLE file.
5. What the file holds is quoted in the log only as sky.parse_tles words its problems
   (bodies.py rule 2): a satellite's name cut short, any other line by its number alone.
6. check-config reads the file with this reader (``warnings``), and shows what its reading
   warned of (a review: it judged the file by ``isfile`` alone: an error page saved as the TLE
   file was "(found)", no warning, and a pipe "does not exist now").
"""

from __future__ import annotations

import logging
import os
import stat
import threading
from pathlib import Path

from bridge.core.readfile import NotRegular, TooLarge, read_regular
from bridge.core.text import shown_path
from bridge.sky import Body, SkyError, parse_tles

log = logging.getLogger(__name__)

MAX_FILE_BYTES = 4 * 1024 * 1024  # rule 4


class CatalogError(ValueError):
    """No such satellite, or no file: the message says which."""


class TleCatalog:
    def __init__(self, path: Path | None, *, logged: bool = True) -> None:
        self.path = path
        self.shown = None if path is None else shown_path(path)  # what it says (core/text.py)
        self._logged = logged  # rule 6: check-config's reading keeps its warnings, unlogged
        self._lock = threading.Lock()  # looked up from paho's thread and rotctld's
        self._seen: tuple[int, int] | None = None
        self._sets: dict[str, tuple[str, str, str]] = {}  # folded name -> (name, line1, line2)
        self._not_read: str | None = None  # rule 4: why the file was not read
        # rule 6: the last read's warnings, as logged (check-config shows them: warnings())
        self._said: list[str] = []

    def names(self) -> list[str]:
        with self._lock:
            self._refresh()
            return sorted({name for name, _l1, _l2 in self._sets.values()})

    def body(self, name: str, tle: tuple[str, str, str] | None = None) -> Body | None:
        """The body ``name`` (or ``tle``) means: the sun, the moon, that element set; None for
        a satellite to look up in the file (on the sky worker). SkyError or CatalogError."""
        if tle is not None:
            return Body.satellite(*tle)
        folded = name.strip().casefold()
        if folded in ("sun", "moon"):
            return Body.sun() if folded == "sun" else Body.moon()
        self.check_configured(name)
        return None

    def check_configured(self, name: str) -> None:
        """CatalogError if there is no file to look ``name`` up in (reads nothing: rule 1)."""
        if self.path is None:
            raise CatalogError(
                f"no satellite {name!r}: no tle_file is configured ([tracking] tle_file); "
                'send the elements as {"tle": ["NAME", "1 ...", "2 ..."]}'
            )

    def warnings(self) -> tuple[int, list[str]]:
        """The file read now as a lookup reads it (rule 6): how many satellites it holds, and
        what that reading warned of. Slow: rule 1."""
        with self._lock:
            self._refresh()
            return len(set(self._sets.values())), list(self._said)

    def _warn(self, text: str) -> None:
        """Rules 2 and 4: said in the log once per change, and kept (rule 6)."""
        self._said.append(text)
        if self._logged:
            log.warning("%s", text)

    def lookup(self, name: str) -> Body:
        """The satellite called ``name`` (CatalogError if there is none). Slow: rule 1."""
        self.check_configured(name)
        with self._lock:
            self._refresh()
            if self._not_read is not None and not self._sets:
                raise CatalogError(f"no satellite {name!r}: {self._not_read}")
            key = _fold(name)
            found = self._sets.get(key)  # a name first, even one of digits ("0815")
            if found is None and key.isdigit():
                found = self._sets.get(key.lstrip("0"))  # then a catalog number
            if found is None:
                count = len(set(self._sets.values()))  # each set is there by name and number
                raise CatalogError(f"no satellite {name!r} in {self.shown} ({count} satellites)")
        try:
            return Body.satellite(*found)
        except SkyError as exc:  # parse_tles checked it already; a defect if it happens
            raise CatalogError(f"{name!r} in {self.shown}: {exc}") from None

    def _refresh(self) -> None:
        """Rule 1 and 2 (under the lock)."""
        if self.path is None:
            return
        try:
            st = os.stat(self.path)
            seen = (st.st_size, st.st_mtime_ns)
            if seen == self._seen:
                return
            data = self._read(st)
        except OSError as exc:
            if self._seen != (-1, -1):
                self._said = []
                self._warn(f"tle_file {self.shown} cannot be read: {exc.strerror or exc}")
                self._seen = (-1, -1)
            return
        self._seen = seen
        self._said = []
        if isinstance(data, str):  # rule 4: not read, said once per change
            self._not_read = data
            self._warn(data)
            return
        self._not_read = None
        text = data.decode("ascii", errors="replace")
        sets, problems = parse_tles(text)
        if problems:  # rule 2: one warning per read, not one per bad line
            many = "y" if len(problems) == 1 else "ies"
            self._warn(
                f"tle_file {self.shown}: {len(problems)} bad entr{many} skipped "
                f"(the first: {problems[0]})"
            )
        self._sets = {}
        for set_name, (line1, line2) in sets.items():
            entry = (set_name, line1, line2)
            self._sets[_fold(set_name)] = entry
        for entry in list(self._sets.values()):  # catalog numbers, after every name
            self._sets.setdefault(entry[1][2:7].strip().lstrip("0"), entry)
        log.info("tle_file %s: %d satellite(s)", self.shown, len(sets))

    def _read(self, seen: os.stat_result) -> bytes | str:
        """The file's bytes, or why they are not read (rule 4); OSError if it cannot be."""
        assert self.path is not None
        limit = f"over the limit of {MAX_FILE_BYTES // (1024 * 1024)} MiB: not read"
        if stat.S_ISREG(seen.st_mode) and seen.st_size > MAX_FILE_BYTES:
            return f"tle_file {self.shown} is {seen.st_size} bytes, {limit}"
        try:  # (core/readfile.py: what is open now is judged, not what was seen)
            return read_regular(self.path, MAX_FILE_BYTES)
        except NotRegular:
            return (
                f"tle_file {self.shown} is no regular file (a device, a pipe or a folder): not read"
            )
        except TooLarge:
            return f"tle_file {self.shown} grew past {MAX_FILE_BYTES} bytes, {limit}"


def _fold(name: str) -> str:
    return name.strip().casefold()
