"""What must survive a restart of the bridge: each rotator's safety lock, the options the
user set (the controller forgets them at power-off, so the bridge re-applies them), a stop owed
to a controller (kept.py rule 8), what rotor
health (session/health.py) has learned of the rotor, the control lease (runtime/lease.py),
the version its controller reported last (rule 12), its places in the order of commands
(rule 14), and a turn a box with no feedback may have in flight (rule 15).

Rules:
1. A small JSON file, replaced atomically on every change: written in full to a temporary file
   beside it, fsynced, renamed over it (and the directory fsynced). A write that fails leaves
   no temporary file behind and the old file as it was. One a process killed mid-write left
   (SIGKILL, the OOM killer, a power cut: one a crash, for years) is named after the file and
   removed by the next start, which holds the installation's lock (rule 7), so it is no other
   process's; another file's in the same directory is left alone, also one whose name begins
   with this one's (``.state.json.<8 hex digits>.tmp`` is the only name removed: a glob on
   ``.state.json.*.tmp`` removed ``state.json.site2``'s, a write of that bridge under way).
2. A missing file means "nothing set" (a lock it does not say may be taken from the broker:
   kept.py rule 10, ``holds_lock``); an unreadable one is reported and treated as empty,
   except that every rotator whose lock state cannot be read starts locked (safety before
   convenience), its status saying why (``problems``), and is written down as locked, so it
   stays locked across restarts until someone unlocks it. A malformed entry (not a table, a
   lock that is not true or false, options that are not on/off, a number or a name, a key
   given twice with two values) does the same for its rotator alone, and the rotator's status
   says why (``problems``). Each such rotator says it once on ``R/error`` too, kind ``state``,
   when it starts (runtime/rotator.py ``start``; the log says it once when the file is read:
   a review found the log and the status alone, and bad input is said on the error topic
   too). Before the bridge first writes over an unreadable file, the file is kept aside, as
   the first free one of ``<name>.unreadable``, ``<name>.unreadable.2`` ... up to
   KEPT_ASIDE_MAX (a hard link, or a copy where the file system has none; the write fails,
   and the file stays, if neither can be made), said in the log: an attack pass pointed
   ``state_file`` at an ADIF logbook, and the start replaced it with the locks, the logbook
   gone. A key given twice is
   read as neither value (core/jsonkeys.py), anywhere in the file: json's own reading keeps the
   last, and a hand-edited ``"locked": true, "locked": false`` started the rotator unlocked.
3. The start proves the file can be written (``check_writable``, an OSError otherwise): the
   content it holds is written as in rule 1, so a full disk or a quota is found at the start,
   not when a lock set for tower work is silently not kept. An unreadable file is not replaced
   by that write (it keeps the next start locked too): the content is written beside it and
   removed.
4. Anything at the path that is not a regular file (a FIFO, a device, a socket, a directory)
   is never opened for reading, which could wait for ever (a FIFO without a writer) or touch
   hardware (a serial device), and never replaced: ``check_writable`` refuses it by its kind.
   So is a symbolic link to nothing (a volume not mounted yet: an attack pass, it was read as
   no file, a kept lock was lost, and the link was replaced by a new file); a link to a file
   is written through, the file replaced, never the link.
5. ``later`` runs a save on the store's own writer thread, in the order asked: a lock or an
   option set from an MQTT callback must not hold that connection (and a stop behind it) for
   an fsync, tens of milliseconds on an SD card. ``flush`` waits for what was asked so far.
   ``queue`` is ``later`` for a rotator's owner step (kept.py rule 5): the save is in line, in
   the order of the decisions, before the step lets go; ``wake`` then starts the writer.
6. The control lease is kept as ``lease``: ``{"operator": ..., "until": <unix seconds>}``. One
   that is malformed is ignored (the lease is free: it only coordinates, and locks nothing).
7. One process runs an installation (``held``): a bridge holds an exclusive lock on ``<state
   file>.lock`` beside its state file while it runs (the kernel lets go when it ends, however it
   ends; the file stays, and one it may not write is locked read-only), and one that finds it
   taken does not start: before it writes the state file (rule 3; its saves until then wait,
   ``deferred``: a last read found a malformed file's replacement written while building the
   rotators), so it cannot undo the running one's last save. An attack pass ran the same
   configuration twice: the two took turns throwing each other off the broker under one client
   id, the real one backing off up to a minute each time, and a STOP that reached the one that
   could not open the port was lost without a word (and both wrote the same state file).
   The lock's file is never opened through a symbolic link (refused, said as such): it is
   emptied for the holder's process id, and a link there (``state.json.lock`` to the audit
   file, a password file) had that file emptied at every start (an attack pass). Such a
   link, or no regular file there (a FIFO, a directory), is refused by ``check_kind`` too, so
   check-config and the build say it as the start does (a review: check-config said "config
   OK", and the start then ended with exit code 2).
8. What the file holds beside ``rotators`` (a newer version's tables) is written back as it
   was read, as a rotator's entry keeps the keys it does not know: an update rolled back, the
   older version's next save dropped them, and the newer one, started again, had lost them.
9. A rotator's entry outlives its rotator (a rotator removed, or renamed: its entry is kept
   by its id): a lock ON kept for an id that no rotator of the configuration has is said in
   the log at every start (app.py, ``locked_ids``), since it locks nothing: a rotator renamed
   while locked for tower work starts as its new id was kept.
10. A number is read as a float whatever its size: an integer too large for one (hundreds of
   digits, a damaged or hand-edited file) is infinite, so a setting's declaration refuses it
   (kept.py rule 1) and a ``short_of`` is none. An attack pass: ``float`` raised
   OverflowError, and the start ended in a traceback, exit code 1, restarted by systemd every
   5 s for ever. An integer longer than Python reads (INT_DIGITS_MAX) is infinite too, not the
   whole file unreadable (a review: every rotator started locked for one such number).
11. The file is read when the bridge is built, and the installation's lock (rule 7) is taken
   when it starts, so a bridge still ending (``kill`` and a start by hand, a script) may write
   in between: ``check_writable``, under the lock, finds the file no longer as it was read
   (``Changed``; a file read whole, not one unreadable, rule 2) and writes nothing, and the
   start ends (exit code 1: systemd starts it again, to read the file as it is now). An
   attack pass: a lock ON the ending bridge saved was written back OFF by the new one, which
   ran unlocked, and a target turned the rotor.
12. A rotator's controller version (kept.py rule 11) is kept as ``version``: ``{"model": <its
   model's name>, "text": ...}``. One kept for another model, or malformed (not such a table,
   a text not printable or longer than VERSION_MAX_CHARS), is none: it is only a name shown
   until the controller answers, so a damaged one is dropped without a word. The limit is
   Home Assistant's longest state: a rotator of two boxes keeps their two versions joined
   (runtime/composite.py rule 3), each up to a line of its protocol (an Easycomm III's 80
   characters), and the 128 it was dropped a pair of two long ones at every start, whose
   discovery then went out twice (an attack pass).
13. A state file under the home folder that is not there yet is read from where versions
   before settings/base.py rule 7 kept one written ``~/...``: a folder named ``~`` under the
   directory the bridge runs from (``tilde_leftover``), said at WARNING; it is written at its
   own path from then on, and the old one is left for the user to delete (review 69: a
   rotator locked there for tower work started unlocked after the update, without a word).
   The installation's lock (rule 7) is taken on both (review 73: an earlier version still
   running on the old file did not stop the start that read it); ``~user/...`` likewise, from
   ``./~user/...``.
14. A rotator's places in the order of commands (runtime/kept.py rule 12) are kept as
   ``order``: ``{"places": <the last place reserved>, "turn": <the place of the turn>,
   "lock": <the place of the lock word>}``, whole numbers not below 0, ``turn`` and ``lock``
   not past ``places``. One that is malformed is none (all 0: the places count from 1, as a
   station that keeps none does, and a remote compares none of them with an earlier run's).
15. A turn a box with no feedback may have had in flight (kept.py rule 13) is kept as
   ``turn_kept``: ``{"boot": <the kernel's boot id>, "until": <when it runs out, seconds on
   CLOCK_BOOTTIME>}``, or no key (none). Not the wall clock (docs/architecture.md rule 15: a
   clock stepped forward, by NTP or by hand, would run it out while the turn may still be
   in flight): the boot clock counts the machine's time since it booted, suspend included,
   and is never set, so it can be compared across a restart of the process on the same
   boot (``boot_clock``; tests inject their own). At a start, one of the same boot whose
   ``until`` is past is none (review 97: a bare true had no end, and a bridge ended within
   its hold kept it for good: a start an hour later stopped a hand at the panel at a
   refused start). One of another boot (the machine restarted: how long it was down is not
   known), a boot clock that cannot be read, ``true`` (kept with no end known yet), or
   anything else there (a damaged entry), or a file that could not be read, is a turn kept:
   the safe side (a refused start in the range's time then stops a box at rest or a hand).
   A clock decides the other way here, where architecture rule 15 lets none: a DCU-1
   answers no question, so no reading can tell; the boot clock is the one that is never
   stepped, and a boot clock past its end, on the same boot, is time that did pass.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import glob
import json
import logging
import math
import os
import secrets
import stat
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from bridge.core.jsonkeys import DuplicateKey, unique_keys
from bridge.core.model import Control, SettingValue
from bridge.core.ondemand import OnDemandThread
from bridge.core.text import shown_path

log = logging.getLogger(__name__)

TEMPORARY_BYTES = 4  # rule 1: the random part of a temporary file's name
KEPT_ASIDE_MAX = 100  # rule 2: unreadable files kept aside beside one state file, at most
VERSION_MAX_CHARS = 255  # rule 12: a longer kept version is none

_KINDS = (
    (stat.S_ISDIR, "directory"),
    (stat.S_ISFIFO, "FIFO"),
    (stat.S_ISCHR, "character device"),
    (stat.S_ISBLK, "block device"),
    (stat.S_ISSOCK, "socket"),
)


def _not_regular(mode: int) -> str | None:
    """What a file of ``mode`` is, if it is not a regular file (rule 4)."""
    if stat.S_ISREG(mode):
        return None
    return next((kind for is_kind, kind in _KINDS if is_kind(mode)), "special file")


def _kind_at(path: Path) -> str | None:
    """What is at ``path`` (symbolic links followed) if it exists and is not a regular file; a
    link to nothing (rule 4)."""
    try:
        return _not_regular(os.stat(path).st_mode)
    except FileNotFoundError:
        if os.path.islink(path):
            return "link to a file that is not there (a volume not mounted yet?)"
        return None
    except OSError as exc:
        if exc.errno == errno.ELOOP:  # (a link that loops)
            return f"link that cannot be followed ({exc.strerror})"
        raise


def _read(path: Path) -> str:
    """The file's text; OSError naming its kind if it is not a regular file (rule 4), also if
    one was put there since it was looked at (O_NONBLOCK: opening a FIFO does not wait)."""
    kind = _kind_at(path)
    if kind is None:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC)
        with os.fdopen(fd, "rb") as f:
            kind = _not_regular(os.fstat(fd).st_mode)
            if kind is None:
                return f.read().decode()
    raise OSError(errno.EINVAL, f"it is a {kind}, not a regular file")


INT_DIGITS_MAX = 4000  # rule 10: a longer integer is read as infinite (Python's int: 4,300)


def _number(value: int | float) -> float:
    """Rule 10: a kept number as a float; an integer too large for one is infinite (no value a
    setting or a bearing takes), not the OverflowError ``float`` raises."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def boot_clock() -> tuple[str, float] | None:
    """Rule 15: the kernel's boot id and its CLOCK_BOOTTIME now; None if either cannot be read
    (then a turn kept is kept: the safe side)."""
    try:
        with open("/proc/sys/kernel/random/boot_id", encoding="ascii") as f:
            boot = f.read().strip()
        now = time.clock_gettime(time.CLOCK_BOOTTIME)
    except (OSError, ValueError, AttributeError):
        return None
    return (boot, now) if boot else None


def _integer(digits: str) -> int | float:
    """Rule 10: a JSON integer; one of more digits than Python reads as an int (4,300: its
    ``int`` refuses more) is infinite, as a float too large for one is."""
    if len(digits.lstrip("-")) > INT_DIGITS_MAX:
        return -math.inf if digits.startswith("-") else math.inf
    return int(digits)


class _TwoValues(list[object]):
    """Rule 2: a JSON object with a key given twice, with two values, as its pairs: no table,
    so whatever holds it is malformed (its entry, its rotator's options) or ignored."""


def _object(pairs: list[tuple[str, object]]) -> dict[str, object] | _TwoValues:
    """``json.loads``' ``object_pairs_hook`` for the state file (rule 2)."""
    try:
        return unique_keys(pairs)
    except DuplicateKey:
        return _TwoValues(pairs)


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a read-only lock file keeps an older run's pid: a last
    read)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True  # (another user's)
    return True


class Changed(Exception):
    """Rule 11: the file is not what this start read from it."""

    def __init__(self, path: Path) -> None:
        super().__init__(f"{shown_path(path)} changed while this bridge started")


def _now_as(path: Path) -> str | None:
    """Rule 11: the file's text now, None if there is none; what cannot be read is no text."""
    try:
        return _read(path)
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return "\0unreadable"  # (no text read from a file: NUL is no JSON)


class InUse(Exception):
    """Rule 7: another process holds this installation's state file."""

    def __init__(self, lock_path: Path, holder: str) -> None:
        super().__init__(f"{shown_path(lock_path)} is held by {holder or 'another process'}")
        self.holder = holder


def _lock_path(path: Path) -> Path:
    """Rule 7: where the installation's lock of the state file ``path`` goes."""
    if path.exists():  # rule 4: beside the file a link names (a review: two installations
        path = Path(os.path.realpath(path))  # naming one file two ways both started)
    return path.with_name(path.name + ".lock")


def _check_lock_kind(lock_path: Path) -> None:
    """Rule 7: OSError if what is at ``lock_path`` is a link, or no regular file (nothing
    there is fine: the start makes it)."""
    if lock_path.is_symlink():
        raise OSError(
            errno.ELOOP, f"{shown_path(lock_path)} is a symbolic link, not a file of its own"
        )
    if _kind_at(lock_path) is not None:
        raise OSError(errno.EINVAL, f"{shown_path(lock_path)} is not a regular file")


@contextlib.contextmanager
def held(path: Path | None) -> Iterator[None]:
    """Rule 7: the installation's lock held for the ``with`` block (nothing without a state
    file); InUse if another process holds it, OSError if it cannot be made."""
    if path is None:
        yield
        return
    lock_path = _lock_path(path)
    lock_path.parent.mkdir(parents=True, exist_ok=True)
    # (a FIFO must not hang the start; a link: rule 7; a tty never becomes ours: review 69)
    flags = os.O_CLOEXEC | os.O_NONBLOCK | os.O_NOFOLLOW | os.O_NOCTTY
    writable = True
    _check_lock_kind(lock_path)
    try:
        fd = os.open(lock_path, os.O_RDWR | os.O_CREAT | flags, 0o644)
    except PermissionError:
        if not lock_path.exists():
            raise  # (the directory is not this user's: said as such)
        # left by root's run by hand: flock needs no write access (a review)
        fd, writable = os.open(lock_path, os.O_RDONLY | flags), False
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(errno.EINVAL, f"{shown_path(lock_path)} is not a regular file")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 64, 0).decode(errors="replace").strip()
            known = holder.isdigit() and _alive(int(holder))  # (not a stale pid)
            raise InUse(lock_path, f"process {holder}" if known else "") from None
        if writable:
            with contextlib.suppress(OSError):  # who holds it, for the next one's message only
                os.ftruncate(fd, 0)
                os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield
    finally:
        os.close(fd)  # (the lock with it)


def tilde_leftover(path: Path | None) -> Path | None:
    """Rule 13: the file an earlier version kept for ``path`` written ``~/...`` or
    ``~user/...``, if ``path`` is under that home folder and not there yet, and that file is;
    else None."""
    if path is None:
        return None
    try:
        if path.exists() or path.is_symlink():
            return None
        here = Path.cwd()
        tildes = [e.name for e in here.iterdir() if e.name.startswith("~") and e.is_dir()]
    except OSError:  # (no working directory)
        return None
    for name in tildes:  # '~' for '~/...', '~user' for '~user/...'
        try:
            old = here / name / path.relative_to(os.path.expanduser(name))
        except ValueError:  # (not under that home; a '~user' naming nobody stays as it is)
            continue
        if old.is_file():
            return old
    return None


class StateStore:
    def __init__(
        self,
        path: Path | None,
        *,
        deferred: bool = False,
        read_from: Path | None = None,
        boot: Callable[[], tuple[str, float] | None] = boot_clock,
    ) -> None:
        """``deferred``: nothing is written before ``check_writable`` (rule 7: the bridge holds
        the installation's lock by then); a save asked before is made then. ``read_from``: the
        file read in place of ``path`` (rule 13), written at ``path``. ``boot``: the boot id
        and the boot clock (rule 15)."""
        self.boot = boot  # rule 15
        if path is not None and read_from is not None:
            log.warning(
                "state file %s: not there yet; read from %s, where an earlier version kept a "
                "state_file written '~/...' (a folder named '~' under the directory it ran "
                "from). Its locks and options hold; the bridge writes them to %s from now on: "
                "delete the old one",
                shown_path(path),
                shown_path(read_from),
                shown_path(path),
            )
        self._path = path
        self._read_path = read_from or path  # rule 11: the file read, looked at again
        self.leftover = read_from  # rule 13: an earlier version's file, read as this one's
        self._deferred = deferred  # rule 7: saves wait for check_writable
        self._owed = False  # a save asked while deferred
        self._lock = threading.Lock()
        self._writer = OnDemandThread("state")  # rule 5
        self._data: dict[str, dict[str, object]] = {}
        self._others: dict[str, object] = {}  # rule 8: tables beside ``rotators``, kept as read
        self.corrupt = False
        self.problems: dict[str, str] = {}  # rotator id -> what was wrong with its entry
        self._unreadable = ""  # rule 2: why the file could not be read, for each rotator locked
        self._aside = False  # rule 2: an unreadable file to keep aside before it is written over
        self._dirty = False  # a malformed entry was replaced: written down at the first read
        self._kind: str | None = None  # not a regular file: refused at the start (rule 4)
        self._read_as: str | None = None  # rule 11: the text read (None: no file, or unread)
        if read_from is not None:
            path = read_from  # (rule 13: read there, written at self._path)
        if path is not None and (path.exists() or path.is_symlink()):
            self._kind = _kind_at(path)
            if self._kind is not None:
                self.corrupt = True  # nothing read: every rotator locked, should it be used
                return
            try:
                text = self._read_as = _read(path)  # rule 11
                loaded = json.loads(text, object_pairs_hook=_object, parse_int=_integer)
                if not isinstance(loaded, dict) or not isinstance(loaded.get("rotators"), dict):
                    raise ValueError("no 'rotators' table")
                self._data = {
                    str(k): self._entry(path, str(k), v) for k, v in loaded["rotators"].items()
                }
                self._others = {k: v for k, v in loaded.items() if k != "rotators"}
            except (OSError, ValueError, RecursionError) as exc:  # (nesting past the parser's
                # depth: a few kilobytes of brackets)
                why = "nested too deep" if isinstance(exc, RecursionError) else exc
                self._unreadable = shown_path(
                    f"state file {path} unreadable ({why}): every rotator starts locked"
                )
                log.error(
                    "%s; the file is kept as %s.unreadable (or .unreadable.2 ...) before the "
                    "bridge writes it anew",
                    self._unreadable,
                    shown_path(os.path.realpath(path)),
                )
                self.corrupt = self._aside = True

    def _entry(self, path: Path, rotator_id: str, entry: object) -> dict[str, object]:
        """One rotator's entry as it must be; one that is not starts that rotator locked."""
        options = entry.get("options", {}) if isinstance(entry, dict) else None
        fine = (
            isinstance(entry, dict)
            and isinstance(entry.get("locked", False), bool)
            and isinstance(options, dict)
            and all(isinstance(v, bool | int | float | str) for v in options.values())
        )
        if fine:
            assert isinstance(entry, dict)
            return entry
        shown = json.dumps(entry)[:80]
        problem = (
            f"state file {shown_path(path)}: entry for {rotator_id!r} is malformed ({shown}): "
            "locked"
        )
        log.error("%s", problem)
        self.problems[rotator_id] = problem
        self._dirty = True
        return {"locked": True}

    def check_kind(self) -> None:
        """OSError if the path can be seen not to work without writing anything: no regular
        file there (rule 4), a file where a directory must be, or a link or no regular file
        where the installation's lock goes (rule 7). check-config asks this."""
        if self._path is None:
            return
        kind = _kind_at(self._path) or self._kind
        if kind is not None:
            raise OSError(errno.EINVAL, f"it is a {kind}, not a regular file")
        _check_lock_kind(_lock_path(self._path))  # rule 7: as the start refuses it

    def check_writable(self) -> None:
        """OSError if the file cannot be written where it is configured (rules 3, 4)."""
        if self._path is None:
            return
        self.check_kind()
        read = self._read_path or self._path
        if self._deferred and not self.corrupt and _now_as(read) != self._read_as:
            raise Changed(self._path)  # rule 11: nothing of this store's written yet
        self._path.parent.mkdir(parents=True, exist_ok=True)
        _remove_leftovers(Path(os.path.realpath(self._path)))  # rule 1
        with self._lock:
            self._write(self._path, put_in_place=not self.corrupt)
            self._dirty = self._dirty and self.corrupt  # malformed entries now written locked
            self._deferred, owed, self._owed = False, self._owed, False
            if owed:  # (rule 7: an unreadable file's locked replacement, asked before)
                self._save()

    def locked(self, rotator_id: str) -> bool:
        with self._lock:
            if self._dirty:  # the replacement of a malformed entry, locked, kept for next time
                self._dirty = False
                self._save()
            entry = self._data.get(rotator_id, {})
            if self.corrupt and "locked" not in entry:
                # written down explicitly, so the next start is locked too until someone unlocks
                self._data.setdefault(rotator_id, {})["locked"] = True
                if self._unreadable:  # rule 2: the rotator's status says why
                    self.problems[rotator_id] = self._unreadable
                self._save()
                return True
            return bool(entry.get("locked", False))

    def holds_lock(self, rotator_id: str) -> bool:
        """Whether the file said the rotator's lock, either way, when read (an unreadable one
        locks every rotator: rule 2); one that did not may have lost it (kept.py rule 10)."""
        with self._lock:
            return self.corrupt or "locked" in self._data.get(rotator_id, {})

    def locked_ids(self) -> set[str]:
        """Rule 9: the rotators the file keeps locked, configured or not."""
        with self._lock:
            return {rid for rid, entry in self._data.items() if entry.get("locked") is True}

    def options(self, rotator_id: str) -> dict[str, SettingValue]:
        """As kept: on/off, a number or a choice's name (kept.py reads them by their model)."""
        raw = self._data.get(rotator_id, {}).get("options", {})
        if not isinstance(raw, dict):
            return {}
        return {
            str(k): (_number(v) if isinstance(v, int) and not isinstance(v, bool) else v)
            for k, v in raw.items()
        }

    def health(self, rotator_id: str) -> dict[str, object] | None:
        """What rotor health kept (health_judge.py reads it, rule 6), if anything."""
        raw = self._data.get(rotator_id, {}).get("health")
        return raw if isinstance(raw, dict) else None

    def set_health(self, rotator_id: str, memory: dict[str, object]) -> bool:
        """Rotor health's memory, on the writer thread (rule 5) after each move."""
        with self._lock:
            self._data.setdefault(rotator_id, {})["health"] = memory
            return self._save()

    def lease(self, rotator_id: str) -> Control | None:
        """Rule 6: the control lease kept for the rotator, if any."""
        raw = self._data.get(rotator_id, {}).get("lease")
        if raw is None:
            return None
        if isinstance(raw, dict):
            operator, until = raw.get("operator"), raw.get("until")
            if isinstance(operator, str) and isinstance(until, (int, float)):
                if not isinstance(until, bool) and abs(until) < 1e300:  # float() can't fail
                    return Control(operator, float(until))
        shown = json.dumps(raw)[:80]  # (as a malformed entry's: a lease of a megabyte, cut)
        log.warning("state file: lease for %r is malformed (%s): ignored", rotator_id, shown)
        return None

    def set_lease(self, rotator_id: str, held: Control | None) -> bool:
        """Rule 6: remember the lease (None: free); False if it could not be written."""
        with self._lock:
            entry = self._data.setdefault(rotator_id, {})
            if held is None:
                entry.pop("lease", None)
            else:
                entry["lease"] = {"operator": held.operator, "until": held.until_unix}
            return self._save()

    def later(self, job: Callable[[], None]) -> None:
        """Rule 5: ``job`` on the writer thread."""
        self._writer.put(job)

    def queue(self, job: Callable[[], None]) -> None:
        """Rule 5: ``job`` in line for the writer thread, which ``wake`` starts (ondemand.py
        rule 4)."""
        self._writer.queue(job)

    def wake(self) -> None:
        """Rule 5: the writer thread for what was queued, if it is not running."""
        self._writer.wake()

    def flush(self, timeout_s: float = 5.0) -> None:
        """Rule 5: the jobs asked so far are done (or ``timeout_s`` passed)."""
        done = threading.Event()
        self.later(done.set)
        done.wait(timeout_s)

    def storm(self, rotator_id: str) -> bool:
        """Whether the rotator was parked for a storm (session/wind.py) when last written."""
        with self._lock:
            return self._data.get(rotator_id, {}).get("storm") is True

    def storm_halted(self, rotator_id: str) -> bool:
        """Whether that storm's park was stopped (a STOP or lock ON: session/wind.py rule 3)."""
        with self._lock:
            return self._data.get(rotator_id, {}).get("storm_halted") is True

    def storm_arrived(self, rotator_id: str) -> bool:
        """Whether that storm's park was seen reached (session/wind.py rule 7): only a true
        says so (anything else, a damaged entry, parks again: the safe side)."""
        with self._lock:
            return self._data.get(rotator_id, {}).get("storm_arrived") is True

    def storm_place(self, rotator_id: str) -> int:
        """The place in the order of commands that storm's park took (kept.py rule 4; 0: none
        known, or a malformed entry)."""
        with self._lock:
            place = self._data.get(rotator_id, {}).get("storm_place")
        return place if type(place) is int and place > 0 else 0

    def set_storm(
        self,
        rotator_id: str,
        storm: bool,
        *,
        halted: bool = False,
        arrived: bool = False,
        place: int = 0,
    ) -> bool:
        """Remember a storm begun or ended, whether its park was stopped, whether it was
        seen reached, and the place its park took (0: none known); False if it could not be
        written."""
        with self._lock:
            entry = self._data.setdefault(rotator_id, {})
            for key, on in (("storm", storm), ("storm_halted", halted), ("storm_arrived", arrived)):
                if storm and on:
                    entry[key] = True
                else:
                    entry.pop(key, None)
            if storm and place > 0:
                entry["storm_place"] = place
            else:
                entry.pop("storm_place", None)
            return self._save()

    def stop_owed(self, rotator_id: str) -> bool:
        """Whether a stop was owed to the rotator when last written (kept.py rule 8); one that
        is not false (a damaged entry) is owed: a stop more is the safe side."""
        with self._lock:
            return self._data.get(rotator_id, {}).get("stop_owed", False) is not False

    def set_stop_owed(self, rotator_id: str, owed: bool) -> bool:
        """Remember a stop owed, or owed no more; False if it could not be written."""
        with self._lock:
            entry = self._data.setdefault(rotator_id, {})
            if owed:
                entry["stop_owed"] = True
            else:
                entry.pop("stop_owed", None)
            return self._save()

    def turn_kept(self, rotator_id: str) -> bool:
        """Whether a turn sent to a box with no feedback may still be in flight (kept.py rule
        13): one kept, unless its ``until`` is past on this same boot (rule 15); one of
        another boot, with no end, a damaged entry, a boot clock not read, or a file that could
        not be read (rule 2), says it may: a stop more is the safe side."""
        with self._lock:
            if self.corrupt:
                return True
            kept = self._data.get(rotator_id, {}).get("turn_kept", False)
        if kept is False:
            return False
        if not isinstance(kept, dict) or set(kept) != {"boot", "until"}:
            return True  # (true: no end known; anything else: damaged)
        boot, until = kept["boot"], kept["until"]
        if not isinstance(boot, str) or not boot or isinstance(until, bool):
            return True
        if not isinstance(until, int | float) or not math.isfinite(until):
            return True
        now = self.boot()
        return now is None or now[0] != boot or now[1] < until

    def set_turn_kept(
        self, rotator_id: str, kept: bool, until: tuple[str, float] | None = None
    ) -> bool:
        """Remember a turn possibly in flight till ``until`` (the boot id, and when it runs out
        on that boot's clock: rule 15; None: no end known), or none; False if it could not be
        written."""
        with self._lock:
            entry = self._data.setdefault(rotator_id, {})
            if not kept:
                entry.pop("turn_kept", None)
            elif until is None:
                entry["turn_kept"] = True
            else:
                entry["turn_kept"] = {"boot": until[0], "until": until[1]}
            return self._save()

    def short_of(self, rotator_id: str) -> float | None:
        """The target the rotor rested short of when last written (kept.py rule 9); None for
        none or a damaged entry."""
        with self._lock:
            value = self._data.get(rotator_id, {}).get("short_of")
        if isinstance(value, bool) or not isinstance(value, int | float):
            return None
        number = _number(value)
        return number if math.isfinite(number) else None

    def set_short_of(self, rotator_id: str, raw_az: float | None) -> bool:
        """Remember it, or that there is none; False if it could not be written."""
        with self._lock:
            entry = self._data.setdefault(rotator_id, {})
            if raw_az is not None:
                entry["short_of"] = raw_az
            else:
                entry.pop("short_of", None)
            return self._save()

    def version(self, rotator_id: str, model: str) -> str | None:
        """Rule 12: the version the rotator's controller reported last, if it was ``model``'s."""
        with self._lock:
            raw = self._data.get(rotator_id, {}).get("version")
        if not isinstance(raw, dict) or raw.get("model") != model:
            return None
        text = raw.get("text")
        if not isinstance(text, str) or not text.isprintable():
            return None
        return text if 0 < len(text) <= VERSION_MAX_CHARS else None

    def set_version(self, rotator_id: str, model: str, version: str) -> bool:
        """Rule 12: remember it; False if it could not be written."""
        with self._lock:
            self._data.setdefault(rotator_id, {})["version"] = {"model": model, "text": version}
            return self._save()

    def order(self, rotator_id: str) -> tuple[int, int, int]:
        """Rule 14: the places kept (reserved, the turn's, the lock word's); all 0 for none or
        a malformed entry."""
        with self._lock:
            raw = self._data.get(rotator_id, {}).get("order")
        if not isinstance(raw, dict):
            return 0, 0, 0
        kept = [raw.get(k) for k in ("places", "turn", "lock")]
        if any(type(n) is not int or n < 0 for n in kept):
            return 0, 0, 0
        places, turn, lock = kept
        assert isinstance(places, int) and isinstance(turn, int) and isinstance(lock, int)
        if turn > places or lock > places:
            return 0, 0, 0
        return places, turn, lock

    def set_order(self, rotator_id: str, places: int, turn: int, lock: int) -> bool:
        """Rule 14: remember them; False if they could not be written."""
        with self._lock:
            entry = self._data.setdefault(rotator_id, {})
            entry["order"] = {"places": places, "turn": turn, "lock": lock}
            return self._save()

    def set_locked(
        self, rotator_id: str, locked: bool, order: tuple[int, int, int] | None = None
    ) -> bool:
        """Remember the lock (and ``order``'s places with it, rule 14, in one write); False if
        it could not be written (it will not survive a restart)."""
        with self._lock:
            entry = self._data.setdefault(rotator_id, {})
            entry["locked"] = locked
            if order is not None:
                places, turn, lock = order
                entry["order"] = {"places": places, "turn": turn, "lock": lock}
            return self._save()

    def set_option(self, rotator_id: str, name: str, enabled: SettingValue) -> bool:
        with self._lock:
            entry = self._data.setdefault(rotator_id, {})
            opts = entry.setdefault("options", {})
            assert isinstance(opts, dict)
            opts[name] = enabled
            return self._save()

    def _save(self) -> bool:
        if self._path is None:
            return True
        if self._deferred:  # rule 7: made by check_writable, once the lock is held
            self._owed = True
            return True
        try:
            self._path.parent.mkdir(parents=True, exist_ok=True)
            self._write(self._path)
            return True
        except OSError as exc:
            log.error("cannot write state file %s", shown_path(f"{self._path}: {exc}"))
            return False

    def _write(self, path: Path, *, put_in_place: bool = True) -> None:
        """The content, in full and on the disk, then renamed over ``path`` (rule 1); without
        ``put_in_place`` it is removed instead (rule 3). OSError if any step fails."""
        whole = {**self._others, "rotators": self._data}  # rule 8
        content = json.dumps(whole, indent=1, sort_keys=True).encode()
        path = Path(os.path.realpath(path))  # rule 4: through a link, never over it
        tmp = path.parent / _temporary(path, secrets.token_hex(TEMPORARY_BYTES))
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o600)
        renamed = False
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(content)
                f.flush()
                os.fsync(f.fileno())
            if put_in_place:
                if self._aside:  # rule 2: never the only copy of what was there
                    aside = _keep_aside(path)
                    if aside is not None:
                        log.warning(
                            "state file %s was unreadable: kept as %s, and written anew",
                            shown_path(path),
                            shown_path(aside.name),
                        )
                os.replace(tmp, path)
                renamed = True
                self._aside = False
        finally:
            if not renamed:
                with contextlib.suppress(OSError):
                    os.unlink(tmp)
        if renamed:
            _sync_directory(path.parent)


def _keep_aside(path: Path) -> Path | None:
    """Rule 2: the file at ``path`` under the first free name of its own kept aside (None: no
    file there any more); OSError if none can be made."""
    for n in range(1, KEPT_ASIDE_MAX + 1):
        aside = path.with_name(f"{path.name}.unreadable" + (f".{n}" if n > 1 else ""))
        try:
            os.link(path, aside)
            return aside
        except FileExistsError:
            continue
        except FileNotFoundError:
            return None
        except OSError:  # a file system without hard links (vfat): a copy
            pass
        try:
            content = path.read_bytes()
        except FileNotFoundError:
            return None
        try:
            fd = os.open(aside, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o600)
        except FileExistsError:
            continue
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(content)
                f.flush()
                os.fsync(f.fileno())
        except OSError:  # (a full disk: no part of a copy left to take the name at each try)
            with contextlib.suppress(OSError):
                os.unlink(aside)
            raise
        return aside
    raise OSError(errno.EEXIST, f"{KEPT_ASIDE_MAX} unreadable files kept aside already")


def _temporary(path: Path, random: str) -> str:
    """Rule 1: the name of a temporary file of ``path``'s around its random part: hex digits,
    TEMPORARY_BYTES of them (a pattern no other state file's temporary names fit)."""
    return f".{path.name}.{random}.tmp"


def _remove_leftovers(path: Path) -> None:
    """Rule 1: the temporary files of ``path``'s a killed process left beside it; no other
    file's (``state.json.site2``'s begin as ``state.json``'s do, and a write of theirs may be
    under way)."""
    pattern = _temporary(Path(glob.escape(path.name)), "[0-9a-f]" * (2 * TEMPORARY_BYTES))
    with contextlib.suppress(OSError):
        for leftover in path.parent.glob(pattern):
            with contextlib.suppress(OSError):
                if stat.S_ISREG(leftover.lstat().st_mode):  # (never what a link names)
                    leftover.unlink()
                    log.info("removed %s, left by a write that was cut short", leftover)


def _sync_directory(directory: Path) -> None:
    """The rename on the disk too; where a file system cannot sync a directory, the file's own
    sync has to do (the rename happened: nothing to report)."""
    with contextlib.suppress(OSError):
        fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
