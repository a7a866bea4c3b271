"""The audit file (``audit_file``): one JSON line per command judged, executed or refused, from
every interface (model.AuditEvent), written by a thread of its own.

Rules:
1. ``put`` never blocks and never raises: it queues the line (a bounded queue, QUEUE_LINES);
   a full queue drops the line and counts it (said in the next line written, ``dropped``). A
   stop, a paho callback or the lines thread never wait for a disk (docs/architecture.md
   rule 12).
2. One event is one line of JSON, whatever text it carries (``audit_line``). Lines are
   appended and flushed one by one (no fsync: a trail, not the state file). Before a
   line that would take the file past ``max_bytes`` the file is rotated: ``audit.jsonl`` becomes
   ``audit.jsonl.1``, that one ``.2``, up to ``keep`` old files; the oldest is deleted.
3. A write that fails (a full disk, a removed directory, no permission) is never fatal: the
   line is dropped, and the failure is reported once (``on_problem``) until a write succeeds
   again; then that is said once too. The file is opened anew for every batch, so a path that
   becomes writable again (space freed, directory made) is used without a restart.
4. ``stop`` writes what is queued, then ends the thread; it waits no longer than its timeout
   (a writer hung on its disk must not hang the bridge's shutdown).
5. ``AuditTrail`` hands each rotator's events to the file (if one is configured) and to a
   publisher (``R/audit``); both only queue. A file that fails is reported (rule 3) on every
   rotator's error topic, kind ``audit``.
"""

from __future__ import annotations

import json
import logging
import os
import queue
import stat
import threading
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Protocol

from bridge.model import AuditEvent, ErrorKind

log = logging.getLogger(__name__)

QUEUE_LINES = 10_000  # rule 1
KEEP_FILES = 3  # rule 2: old files kept beside the current one
_STOP = object()


_LINE_BREAKS = str.maketrans({"\x85": "\\u0085", "\u2028": "\\u2028", "\u2029": "\\u2029"})


def audit_line(doc: dict[str, object]) -> str:
    """An event as one JSON line (rule 2): besides what JSON escapes, the characters other
    readers break lines at (str.splitlines, editors) are escaped too."""
    return json.dumps(doc, separators=(",", ":"), ensure_ascii=False).translate(_LINE_BREAKS)


class AuditFile:
    def __init__(
        self,
        path: Path,
        max_bytes: int,
        *,
        keep: int = KEEP_FILES,
        on_problem: Callable[[str | None], None] | None = None,
        queue_lines: int = QUEUE_LINES,
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
                self._write(events)
            for item in batch:
                if isinstance(item, threading.Event):
                    item.set()
            if any(item is _STOP for item in batch):
                return

    def _write(self, events: list[AuditEvent]) -> None:
        lines = []
        for event in events:
            doc = event.as_dict()
            if self._dropped:  # rule 1 (read and reset here only: a count, not a promise)
                doc["dropped"], self._dropped = self._dropped, 0
            lines.append(audit_line(doc) + "\n")
        try:
            self._append(lines)
        except OSError as exc:
            self.lines_lost += len(lines)
            if not self._failing:  # rule 3: once
                self._failing = True
                problem = f"audit file {self.path} cannot be written ({exc}): lines are lost"
                log.error("%s", problem)
                if self._on_problem is not None:
                    self._on_problem(problem)
            return
        self.lines_written += len(lines)
        if self._failing:
            self._failing = False
            log.warning("audit file %s is written again", self.path)
            if self._on_problem is not None:
                self._on_problem(None)

    def _append(self, lines: list[str]) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        out = None
        try:
            for line in lines:
                data = line.encode()
                if out is None:
                    size = self._size()
                    if size and size + len(data) > self._max_bytes:
                        self._rotate()
                        size = 0
                    out = open(self.path, "ab")  # noqa: SIM115  # closed below
                    written = size
                elif written and written + len(data) > self._max_bytes:
                    out.close()
                    self._rotate()
                    out, written = open(self.path, "ab"), 0  # noqa: SIM115
                out.write(data)
                out.flush()  # rule 2: a line at a time reaches the system (and ENOSPC here)
                written += len(data)
        finally:
            if out is not None:
                out.close()

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
        """The ``on_audit`` of one rotator (engine/operators.py)."""
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
