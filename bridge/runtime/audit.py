"""The audit file (``audit_file``): one JSON line per command judged, executed or refused, from
every interface (model.AuditEvent), written by a thread of its own.

Rules:
1. ``put`` never blocks and never raises: it queues the line (a bounded queue, QUEUE_LINES);
   a full queue drops the line and counts it (said in the next line written, ``dropped``). A
   stop, a paho callback or the lines thread never wait for a disk (docs/architecture.md
   rule 12).
2. One event is one line of JSON, whatever text it carries (``audit_line``). Each line is one
   ``os.write`` on a descriptor opened with O_APPEND (no fsync: a trail, not the state file),
   so it reaches the file whole or not at all. Before a
   line that would take the file past ``max_bytes`` the file is rotated: ``audit.jsonl`` becomes
   ``audit.jsonl.1``, that one ``.2``, up to ``keep`` old files; the oldest is deleted.
3. A write that fails (a full disk, a removed directory, no permission) is never fatal (nor is
   a bug in making a batch's lines: logged, its lines lost and counted, the writer goes on): the
   file is cut back to its size before that line (a short write on a full disk leaves no torn
   line), the line and the rest of its batch are dropped and counted (``lines_lost``,
   ``write_failures``), and the failure is reported once (``on_problem``) until a write
   succeeds again; then that is said once too, in the log with the counts, and the first line
   written says how many were lost (``dropped``). The file is opened anew for every batch, so
   a path that becomes writable again (space freed, directory made) is used without a restart.
   It is opened non-blocking: a named pipe at the path with no reader, or one that does not
   read, is such a failure too (an attack pass: the writer hung in its open, forever, nothing
   was said, and every line after was lost).
4. ``stop`` writes what is queued, then ends the thread; it waits no longer than its timeout
   (a writer hung on its disk must not hang the bridge's shutdown).
5. ``AuditTrail`` hands each rotator's events to the file (if one is configured) and to a
   publisher (``R/audit``); both only queue. A file that fails is reported (rule 3) on every
   rotator's error topic, kind ``audit``.
"""

from __future__ import annotations

import errno
import json
import logging
import os
import queue
import re
import stat
import threading
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Protocol

from bridge.core.model import AuditEvent, ErrorKind

log = logging.getLogger(__name__)

QUEUE_LINES = 10_000  # rule 1
KEEP_FILES = 3  # rule 2: old files kept beside the current one
_STOP = object()
# rule 3: O_NONBLOCK changes nothing for a file; a FIFO at the path (no reader, or one that
# never reads) fails its open or write at once instead of hanging the writer unsaid
_FLAGS = os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NONBLOCK


_LINE_BREAKS = str.maketrans({"\x85": "\\u0085", "\u2028": "\\u2028", "\u2029": "\\u2029"})
_SURROGATE = re.compile("[\ud800-\udfff]")


def audit_line(doc: dict[str, object]) -> str:
    """An event as one JSON line (rule 2): besides what JSON escapes, the characters other
    readers break lines at (str.splitlines, editors) are escaped too, and so is a lone
    surrogate (a JSON ``\\ud800`` in a payload: no UTF-8 has it, and writing it raised)."""
    line = json.dumps(doc, separators=(",", ":"), ensure_ascii=False).translate(_LINE_BREAKS)
    return _SURROGATE.sub(lambda m: f"\\u{ord(m.group()):04x}", line)


class AuditFile:
    def __init__(
        self,
        path: Path,
        max_bytes: int,
        *,
        keep: int = KEEP_FILES,
        on_problem: Callable[[str | None], None] | None = None,
        queue_lines: int = QUEUE_LINES,
        os_write: Callable[[int, bytes], int] = os.write,
    ) -> None:
        """``on_problem``: a message when writing fails (rule 3), None when it works again."""
        self.path = path
        self._max_bytes = max_bytes
        self._keep = keep
        self._on_problem = on_problem
        self._queue: queue.Queue[object] = queue.Queue(maxsize=queue_lines)
        self._dropped = 0  # rule 1: since the last line written
        self._failing = False  # rule 3
        self.lines_written = 0
        self.lines_lost = 0  # dropped by a full queue or a failed write
        self.write_failures = 0  # rule 3: writes that failed (each ends its batch)
        self._unsaid = 0  # rule 3: lines lost to failed writes, not said in a line yet
        self._os_write = os_write  # (tests give a disk that fails their way)
        self._thread = threading.Thread(target=self._run, name="audit", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout_s: float = 5.0) -> None:
        """Rule 4."""
        if not self._thread.is_alive():
            return
        try:  # full: the writer drains it, unless it hangs on its disk (then give up)
            self._queue.put(_STOP, timeout=timeout_s)
        except queue.Full:
            log.error("audit file %s: the writer does not answer; lines may be lost", self.path)
            return
        self._thread.join(timeout_s)

    def put(self, event: AuditEvent) -> None:
        """Rule 1: queue the event; never blocks."""
        try:
            self._queue.put_nowait(event)
        except queue.Full:
            self._dropped += 1
            self.lines_lost += 1

    def flush(self, timeout_s: float = 5.0) -> None:
        """What was put so far is written (or failed): for tests and shutdown."""
        done = threading.Event()
        try:
            self._queue.put(done, timeout=timeout_s)
        except queue.Full:
            return
        done.wait(timeout_s)

    # -- the writer thread --------------------------------------------------------------------
    def _run(self) -> None:
        while True:
            batch = [self._queue.get()]
            while True:  # whatever else waits: one open of the file for all of it
                try:
                    batch.append(self._queue.get_nowait())
                except queue.Empty:
                    break
            events = [e for e in batch if isinstance(e, AuditEvent)]
            if events:
                try:
                    self._write(events)
                except Exception:  # rule 3: a bug costs its batch, never the writer
                    self.lines_lost += len(events)
                    self._unsaid += len(events)
                    log.exception("audit file %s: %d line(s) lost", self.path, len(events))
            for item in batch:
                if isinstance(item, threading.Event):
                    item.set()
            if any(item is _STOP for item in batch):
                return

    def _write(self, events: list[AuditEvent]) -> None:
        lines = []
        carried = 0  # rule 3: lines lost before, said in the first line written
        for event in events:
            try:
                doc = event.as_dict()
                if self._dropped or self._unsaid:  # rule 1 (read and reset here only: a
                    doc["dropped"] = self._dropped + self._unsaid  # count, not a promise)
                line = audit_line(doc)
            except Exception:  # rule 3: a bug costs its line, counted in the next one
                self.lines_lost += 1
                self._unsaid += 1
                log.exception("audit file %s: a line lost", self.path)
                continue
            if "dropped" in doc:
                carried, self._dropped, self._unsaid = self._dropped + self._unsaid, 0, 0
            lines.append(line + "\n")
        done, exc = self._append(lines)
        self.lines_written += done
        if exc is not None:  # rule 3
            lost = len(lines) - done
            self.lines_lost += lost
            self.write_failures += 1
            self._unsaid = lost + (carried if done == 0 else 0)  # a lost line's count goes on
            if not self._failing:  # once
                self._failing = True
                problem = f"audit file {self.path} cannot be written ({exc}): lines are lost"
                log.error("%s", problem)
                if self._on_problem is not None:
                    self._on_problem(problem)
            return
        if self._failing:
            self._failing = False
            log.warning(
                "audit file %s is written again; %d line(s) lost in all (%d failed write(s))",
                self.path,
                self.lines_lost,
                self.write_failures,
            )
            if self._on_problem is not None:
                self._on_problem(None)

    def _append(self, lines: list[str]) -> tuple[int, Exception | None]:
        """Rule 2: the lines appended, one ``os.write`` each on an O_APPEND descriptor; how many
        were, and the error that ended it (rule 3: the file is cut back to the line before)."""
        fd, done, size = -1, 0, 0
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            for line in lines:
                data = line.encode()
                if fd < 0 or (size and size + len(data) > self._max_bytes):
                    if fd >= 0:
                        os.close(fd)
                        fd = -1
                    size = self._size()
                    if size and size + len(data) > self._max_bytes:
                        self._rotate()
                        size = 0
                    fd = os.open(self.path, _FLAGS, 0o644)
                self._append_line(fd, data)
                size += len(data)
                done += 1
        except Exception as exc:  # (rule 3: whatever a write raises, not only OSError)
            return done, exc
        finally:
            if fd >= 0:
                os.close(fd)
        return done, None

    def _append_line(self, fd: int, data: bytes) -> None:
        """Rule 3: a line is written whole or not at all: after a failed or short write the
        file is cut back to its size before it (no torn line for a reader, nor for the next
        line to land on)."""
        before = os.fstat(fd).st_size
        try:
            written = self._os_write(fd, data)
        except Exception:
            _cut(fd, before)
            raise
        if written != len(data):
            _cut(fd, before)
            raise OSError(errno.ENOSPC, f"short write ({written} of {len(data)} bytes)")

    def _size(self) -> int:
        """The current file's size: 0 for none, and for what is not a regular file (a directory
        there is never rotated away; /dev/full is written to, and fails: rule 3)."""
        try:
            st = self.path.stat()
        except FileNotFoundError:
            return 0
        return st.st_size if stat.S_ISREG(st.st_mode) else 0

    def _rotate(self) -> None:
        """Rule 2: the current file becomes .1, .1 becomes .2, ...; the oldest goes."""
        oldest = self.path.with_name(f"{self.path.name}.{self._keep}")
        if self._keep < 1:
            os.unlink(self.path)
            return
        if oldest.exists():
            oldest.unlink()
        for n in range(self._keep - 1, 0, -1):
            older = self.path.with_name(f"{self.path.name}.{n}")
            if older.exists():
                older.replace(self.path.with_name(f"{self.path.name}.{n + 1}"))
        self.path.replace(self.path.with_name(f"{self.path.name}.1"))


def _cut(fd: int, size: int) -> None:
    """Cut a regular file back to ``size`` (best effort: the failure is already reported)."""
    try:
        if stat.S_ISREG(os.fstat(fd).st_mode):
            os.ftruncate(fd, size)
    except OSError as exc:
        log.debug("audit file: cutting back to %d bytes failed: %s", size, exc)


class Reporter(Protocol):
    def report(self, kind: ErrorKind, message: str, command: str | None) -> None: ...


class AuditTrail:
    """Rule 5: where every rotator's audit events go."""

    def __init__(
        self,
        path: Path | None,
        max_bytes: int,
        publish: Callable[[str, AuditEvent], None],
        rotators: Sequence[Reporter],
    ) -> None:
        """``publish(rotator_id, event)``; ``rotators``: those told when the file fails (the
        app's list, filled after this)."""
        self._publish = publish
        self._rotators = rotators
        self.file: AuditFile | None = None
        if path is not None:
            self.file = AuditFile(path.expanduser(), max_bytes, on_problem=self._failed)

    def _failed(self, problem: str | None) -> None:
        for rot in self._rotators if problem is not None else ():  # None: it works again
            rot.report(ErrorKind.AUDIT, problem or "", None)

    def of(self, rotator_id: str) -> Callable[[AuditEvent], None]:
        """The ``on_audit`` of one rotator (runtime/operators.py)."""
        return partial(self._audited, rotator_id)

    def _audited(self, rotator_id: str, event: AuditEvent) -> None:
        if self.file is not None:
            self.file.put(event)
        self._publish(rotator_id, event)

    def start(self) -> None:
        if self.file is not None:
            self.file.start()

    def stop(self) -> None:
        if self.file is not None:
            self.file.stop()

    def flush(self, timeout_s: float = 5.0) -> None:
        if self.file is not None:
            self.file.flush(timeout_s)
