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
6. A flood does not erase the trail (an attack pass: 1,000 console STOPs a second rolled all
   four files over in 25 s, and the line of who turned the rotor a minute before was gone).
   ``AuditTrail`` folds what a flood is made of, a refusal, an executed stop or a halt that
   changed nothing (rule 10) (``AuditEvent.routine``), per rotator, sender (``Origin``:
   interface, operator, address) and kind (refused, stop, each such halt's command): a run's
   first FREE_LINES events are written one by one, the
   rest are counted; when the run has been quiet for QUIET_S, and every SPAN_S while it goes
   on, one line stands for those counted: the last of them with ``count``, ``first`` and
   ``last`` (their times; written then, so maybe after lines of later times). A move (but the
   same target again, rule 9), a lease change, a lock change, a tracking or following OFF that
   ended something (anything else) is never folded,
   and one sender's run never
   folds another's events. More than MOST_RUNS runs open at once (senders without number:
   an operator name per message) fold by interface and kind alone, the line ``mixed`` and
   named by the interface; while that crowd's run goes on, a sender new to that interface
   and kind joins it (a name used once each, every QUIET_S, was a line each). A sender whose
   run was open before goes on in its own. A run is kept in memory only: the stop writes
   every run's count; a crash loses the counts of runs still open (the first lines of each
   are written). Both the file and ``R/audit`` get the same lines.
7. The thread that says rule 6's summaries ("audit-runs") sleeps until the next one is due
   (``Runs.left``: a run's QUIET_S or SPAN_S), each sleep TICK_S at least (many runs whose
   deadlines follow each other closely, a crowd's, would wake it for each: a summary is then
   up to TICK_S late, as it always was); and, while no run is open, without
   a deadline: an idle bridge never wakes it (it woke once a second for nothing, 16 rotators
   or one). The event that opens the first run wakes it; a run opened later is never due
   sooner than those open (its deadline is QUIET_S from now, theirs at most that), so no
   other event does. The stop wakes it too, and then says every open run's count (rule 6).
8. A crowd's line (rule 6's ``mixed``) says whom it stands for, so that an operator reading the
   trail after a flood learns who (it said the interface alone): ``senders``, how many
   different senders (operator and address) sent the events it counts, counted up to
   SENDERS_COUNTED (beyond, ``more_senders``: more, uncounted), and ``names``, the first NAMED
   of them as they came (their ``who``; an operator and an address, both). Bounded however
   many send: a crowd's run keeps SENDERS_COUNTED hashes and NAMED names at most (a name is 32
   characters at most, an address a few dozen), forgotten with each summary.
9. Nor does a program that sends the same target over and over (a Node-RED loop that
   republishes a slider's value 50 times a second: 50 lines a second, the four files rolled
   over in 8 minutes, in 48 s at 500 a second). An absolute target (``AuditEvent.same_again``)
   that is the one its sender sent last, with nothing carried out on that rotator since
   (anyone's other target, a stop, a lock, a setting; a refusal changes nothing and does not
   count), is folded as rule 6 folds a run: one run per rotator, sender and target, its first
   FREE_LINES written, then a count line, never a crowd's (beyond MOST_RUNS runs, written).
   Such a repeat tells nothing the line before it did not: who sent the rotor where is the
   first one's line, and a repeat after anything else is written again (it may turn the rotor
   back: after another sender's target, a stop). A crash loses only the count. A stream of
   different targets (a tracker computing a bearing 50 times a second) is not folded: the
   audit sees a target when it is taken, not whether it reached the controller (the session
   sends a stream of targets at its pauses and, while it goes on, about once a second:
   session/targets.py rule 2). The same holds for the other commands that change nothing when
   sent again (``same_again``): the holder's claim renewed again and again, a lock OFF while
   unlocked, a release of a lease nobody holds, a setting to the value it has (a second attack
   pass: 32,000 releases from one client rolled the four files over in 6.2 s, and the line of
   who turned the rotor was gone), and the halts of rule 10 (a lock ON, tracking OFF,
   following OFF) that changed nothing (``unchanged``), whether or not the first of them
   changed anything: those fold in rule 10's run, one for the loop whether or not each is
   sent again. A halt the judge says changed something is never rule 9's, sent again or not
   (a review: a loop's lock ON that gave up a storm's park begun in between was folded into
   the loop's count, and nothing said who stopped the park). Not a nudge, a preset or a
   park: each again may turn the rotor anew.
10. Nor does a halt that changed nothing (``AuditEvent.unchanged``, judged where the command is
   carried out: runtime/rotator.py): a lock ON while the lock was ON (and no storm's park was owed,
   which a lock ON ends: session/wind.py rule 3; nor a live wind reading on its way that the status
   does not show yet, session/mailbox.py rule 9: its park may be the one ended), a tracking OFF
   while nothing was tracked nor looked up, a following OFF while nothing was followed (in either
   box of a rotator of two), from any interface (MQTT, a lock switch's loop; the console, a group's
   member, the remote's words as they reach the station). A third attack pass: 400 ``R/lock ON``
   while locked were 400 lines, as were 400 ``track off`` and 400 ``follow off`` with nothing to
   end; a loop republishing them rolls the four files over as rule 6's STOPs did. Such a halt is
   folded as rule 6 folds a stop (one run per rotator, sender and command, its first FREE_LINES
   written, a crowd's beyond MOST_RUNS), and sent again it is rule 9's too; the command is the one
   read (``AuditEvent.folds_as``: ``track off``, ``follow OFF``, a lock word), not the payload as it
   came (a review: 400 ``track off`` each padded with other whitespace or case were 400 runs of one
   line; the line still shows the sender's words); ``R/audit`` counts it with the refusals and
   stops, never against the budget that keeps the moves (interfaces/mqtt/service.py rule 8: 200
   ``track off`` left the lease holder's move out). A lock ON that locked, an OFF that ended
   tracking or following, is a line of its own. An OFF judged while a start is on its way to the
   session, or put while one comes, is taken to have ended it (never folded for a start it may have
   ended).
11. A path that names one of the process's own descriptors (core/readfile.py ``stream_fd``:
   ``/dev/stdout``, ``/dev/stderr``, ``/dev/fd/N``, ``/proc/self/fd/N``, by name) is that
   descriptor: the lines are written on a copy of it (``os.dup``), never by opening the path, and
   it is never rotated (review 87: a user may want the trail in the journal; opening
   ``/dev/stdout`` on the journal's socket fails, ENXIO, and settings rule 6 judged the name by
   where the checking process's own stdout went). It is the process's stream as it was started: a
   write blocks while its reader does not read (the writer's thread alone waits: rule 1), and one
   that fails (no reader, a closed descriptor) is rule 3's failure.
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
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Protocol

from bridge.core.model import AuditEvent, ErrorKind, Origin
from bridge.core.readfile import stream_fd
from bridge.core.text import shown_path

log = logging.getLogger(__name__)

QUEUE_LINES = 10_000  # rule 1
KEEP_FILES = 3  # rule 2: old files kept beside the current one
FREE_LINES = 5  # rule 6: like events of one sender written one by one before they are folded
QUIET_S = 5.0  # rule 6: a run ends after this long without a like event
SPAN_S = 60.0  # rule 6: a run that goes on is summed up this often
MOST_RUNS = 256  # rule 6: runs open at once; beyond, one run per interface and kind
SENDERS_COUNTED = 1000  # rule 8: a crowd's different senders counted (beyond: more_senders)
NAMED = 5  # rule 8: a crowd's first senders named on its line
TICK_S = 1.0  # rule 7: the ticker wakes at most this often while runs are open
Said = tuple[str, AuditEvent]  # (rotator id, event): a line to write and publish
_STOP = object()
# rule 3: O_NONBLOCK changes nothing for a file; a FIFO at the path (no reader, or one that
# never reads) fails its open or write at once instead of hanging the writer unsaid
_FLAGS = os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC


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
        self.shown = shown_path(path)  # what it says of the file (core/text.py)
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
            log.error("audit file %s: the writer does not answer; lines may be lost", self.shown)
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
                    log.exception("audit file %s: %d line(s) lost", self.shown, len(events))
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
                log.exception("audit file %s: a line lost", self.shown)
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
                problem = shown_path(
                    f"audit file {self.path} cannot be written ({exc}): lines are lost"
                )
                log.error("%s", problem)
                if self._on_problem is not None:
                    self._on_problem(problem)
            return
        if self._failing:
            self._failing = False
            log.warning(
                "audit file %s is written again; %d line(s) lost in all (%d failed write(s))",
                self.shown,
                self.lines_lost,
                self.write_failures,
            )
            if self._on_problem is not None:
                self._on_problem(None)

    def _append(self, lines: list[str]) -> tuple[int, Exception | None]:
        """Rule 2: the lines appended, one ``os.write`` each on an O_APPEND descriptor; how many
        were, and the error that ended it (rule 3: the file is cut back to the line before)."""
        fd, done, size = -1, 0, 0
        stream = stream_fd(self.path)  # rule 11: written on, never opened nor rotated
        try:
            if stream is not None:
                fd = os.dup(stream)
            else:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            for line in lines:
                data = line.encode()
                if stream is None and (fd < 0 or (size and size + len(data) > self._max_bytes)):
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


@dataclass
class _Run:
    """Rule 6: the like events of one sender and kind, as they come."""

    began: float  # (the monotonic clock) this run's span began
    seen: float  # the latest like event came
    written: int = 0  # written one by one (FREE_LINES at most)
    folded: int = 0  # since the last summary
    first_unix: float | None = None  # the first of those folded (its event's time)
    last: AuditEvent | None = None  # the latest folded
    # rule 8 (a crowd's run only): the senders of those folded, by their hash, the first named
    senders: set[int] = field(default_factory=set)
    more_senders: bool = False
    names: list[str] = field(default_factory=list)

    def fold_sender(self, origin: Origin, counted: int, named: int) -> None:
        """Rule 8: one more folded event of a crowd, from ``origin``."""
        sender = hash(
            (origin.operator, origin.peer)
        )  # (str hashes are keyed: none can be aimed at)
        if sender in self.senders:
            return
        if len(self.senders) >= counted:
            self.more_senders = True
            return
        self.senders.add(sender)
        if len(self.names) < named:
            both = origin.operator and origin.peer
            self.names.append(f"{origin.operator} ({origin.peer})" if both else origin.who)


class Runs:
    """Rule 6, pure (the caller holds a lock and gives the clock's time): which events are
    written and which are folded into a run's summary."""

    def __init__(
        self,
        *,
        free: int = FREE_LINES,
        quiet_s: float = QUIET_S,
        span_s: float = SPAN_S,
        most: int = MOST_RUNS,
        counted: int = SENDERS_COUNTED,
        named: int = NAMED,
    ) -> None:
        self._free = free
        self._counted = counted
        self._named = named
        self._quiet_s = quiet_s
        self._span_s = span_s
        self._most = most
        self._runs: dict[tuple[str, Origin, str, bool], _Run] = {}
        # rule 9: each rotator's latest event that was carried out: (sender, command, result)
        # when it was one that changes nothing sent again (``same_again``), None when not
        self._latest: dict[str, tuple[Origin, str, str] | None] = {}

    def offer(self, rotator_id: str, event: AuditEvent, now: float) -> list[Said]:
        """What to write and publish now for ``event`` (the summaries of runs that ended
        first, then the event itself unless it is folded)."""
        out = self.due(now)
        again = self._again(rotator_id, event)  # rule 9
        if not event.routine and not again:  # a move, a lease or a lock change: its own line
            return [*out, (rotator_id, event)]
        if again and not event.unchanged:  # rule 9: one sender's one command, never a crowd's
            key = (rotator_id, event.origin, f"again {event.folds_as}", False)
            if key not in self._runs and len(self._runs) >= self._most:
                return [*out, (rotator_id, event)]
        else:
            # (rule 10: a halt that changed nothing, a run of each command, apart from stops;
            # sent again too, rule 9's: one run for a loop of them)
            kind = "stop" if event.halt else "refused"
            kind = f"unchanged {event.folds_as}" if event.unchanged else kind
            key = (rotator_id, event.origin, kind, False)
            crowd = (rotator_id, Origin(event.origin.interface), kind, True)
            if key not in self._runs and (len(self._runs) >= self._most or crowd in self._runs):
                key = crowd  # senders beyond counting, until their interface's crowd is quiet
        run = self._runs.get(key)
        if run is None:
            run = self._runs[key] = _Run(now, now)
        run.seen = now
        if run.written < self._free:
            run.written += 1
            return [*out, (rotator_id, event)]
        run.folded += 1
        if key[3]:  # rule 8
            run.fold_sender(event.origin, self._counted, self._named)
        if run.first_unix is None:
            run.first_unix = event.time_unix
        run.last = event
        return out

    def _again(self, rotator_id: str, event: AuditEvent) -> bool:
        """Rule 9: whether ``event`` is the command its sender had carried out last, nothing else
        carried out on that rotator since (what was refused changed nothing); notes it as the
        latest."""
        if event.result.startswith("refused"):
            return False
        this = (event.origin, event.folds_as, event.result) if event.same_again else None
        before = self._latest.get(rotator_id)
        self._latest[rotator_id] = this
        return this is not None and this == before

    @property
    def open(self) -> bool:
        """Rule 7: whether any run is open (the ticker has something to wait for)."""
        return bool(self._runs)

    def left(self, now: float) -> float | None:
        """How long until a run's summary is due (its QUIET_S or its SPAN_S, whichever comes
        first; 0 when one is due now); None while no run is open (rule 7: nothing to wait for)."""
        if not self._runs:
            return None
        due = min(min(r.seen + self._quiet_s, r.began + self._span_s) for r in self._runs.values())
        return max(0.0, due - now)

    def due(self, now: float, *, everything: bool = False) -> list[Said]:
        """The summaries of runs that ended (quiet for QUIET_S) or have run SPAN_S (said, and
        folding on); ``everything``: of all (the bridge stops)."""
        out: list[Said] = []
        for key, run in list(self._runs.items()):
            # (as ``left`` reckons them, to the last bit: a run ``left`` calls due is said)
            quiet = everything or run.seen + self._quiet_s <= now
            if not quiet and run.began + self._span_s > now:
                continue
            if run.folded and run.last is not None:
                mixed = key[3]
                last = run.last
                origin = Origin(last.origin.interface) if mixed else last.origin
                said = replace(
                    last,
                    origin=origin,
                    count=run.folded,
                    first_unix=run.first_unix,
                    mixed=mixed,
                    senders=len(run.senders),
                    more_senders=run.more_senders,
                    names=tuple(run.names),
                )
                out.append((key[0], said))
            if quiet:
                del self._runs[key]
            else:
                run.began, run.folded, run.first_unix, run.last = now, 0, None, None
                run.senders, run.more_senders, run.names = set(), False, []
        return out


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
        *,
        clock: Callable[[], float] = time.monotonic,
        runs: Runs | None = None,
    ) -> None:
        """``publish(rotator_id, event)``; ``rotators``: those told when the file fails (the
        app's list, filled after this)."""
        self._publish = publish
        self._rotators = rotators
        self._clock = clock
        self._runs = Runs() if runs is None else runs  # rule 6
        self._runs_lock = threading.Lock()
        self._runs_changed = threading.Condition(self._runs_lock)  # rule 7: a run opened, the stop
        self._ended = False
        self.ticker_asleep = False  # rule 7: the ticker waits (tests read these)
        self.ticker_timeout: float | None = None  # ... this long (None: until a run opens)
        self.ticker_wakeups = 0  # ... and came back from its wait this often
        self._ticker = threading.Thread(target=self._tick_on, name="audit-runs", daemon=True)
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
        with self._runs_changed:  # rule 6 (a few dictionary look-ups: never a wait)
            idle = not self._runs.open
            said = self._runs.offer(rotator_id, event, self._clock())
            if idle and self._runs.open:  # rule 7: the first run opened wakes the ticker
                self._runs_changed.notify()
        self._say(said)

    def _say(self, said: list[Said]) -> None:
        for rotator_id, event in said:
            if self.file is not None:
                self.file.put(event)
            self._publish(rotator_id, event)

    def tick(self, *, everything: bool = False) -> None:
        """Rule 6: the summaries of the runs that ended, said (when due, rule 7, and at the
        stop)."""
        with self._runs_lock:
            said = self._runs.due(self._clock(), everything=everything)
        self._say(said)

    def _tick_on(self) -> None:
        """Rule 7: asleep until a summary is due, or without a deadline while no run is open."""
        while True:
            with self._runs_changed:
                if self._ended:
                    return
                timeout = self._runs.left(self._clock())
                if timeout != 0.0:  # nothing due yet: sleep until it is, or a run opens
                    timeout = None if timeout is None else max(timeout, TICK_S)
                    self.ticker_timeout, self.ticker_asleep = timeout, True
                    self._runs_changed.wait(timeout)
                    self.ticker_asleep = False
                    self.ticker_wakeups += 1
                    continue  # (woken by a run that opened: its summary is not due yet)
            try:
                self.tick()
            except Exception:  # (rule 3's spirit: a bug costs a summary, never the ticker)
                log.exception("audit: a run's summary lost")

    def start(self) -> None:
        if self.file is not None:
            self.file.start()
        self._ticker.start()

    def stop(self) -> None:
        with self._runs_changed:
            self._ended = True
            self._runs_changed.notify()
        if self._ticker.is_alive():
            self._ticker.join(5.0)
        self.tick(everything=True)  # rule 6: the counts of runs still open are written too
        if self.file is not None:
            self.file.stop()

    def flush(self, timeout_s: float = 5.0) -> None:
        if self.file is not None:
            self.file.flush(timeout_s)
