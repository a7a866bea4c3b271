"""The pseudo-terminal side of the text front ends (GS-232B, Easycomm II): one pty per rotator
and protocol, a symlink at the configured path for programs that want a serial port
(``rotctl -m 603 -r /tmp/rotor-gs232``, PstRotator under Wine, a logger's COM port), served by
one thread with the same sessions as the TCP ports (tcplines.LineSession).

What the bytes mean is not decided here: the front end hands a session factory (gs232/); this
module owns the pty, its link and its thread.

Rules:
1. ``listen`` opens the pty pair (raw: no echo, no line editing, no CR/LF translation) and links
   the slave's name at the path: a symlink already there (a leftover from a crash) is
   replaced in one step (os.replace), anything else there is refused, untouched, with an
   OSError naming the front end, the rotator, the path and the setting to change. A link a
   live server serves is no leftover: each server claims its path for as long as it lives (a
   Linux abstract socket named after the path, which dies with its process, so a crash leaves
   no claim), and a path claimed already is refused (EADDRINUSE). Where there are no abstract
   sockets (macOS) a link there is replaced as before. The claim's name hashes the path's
   bytes (``os.fsencode``), not its UTF-8 text: a path may be any bytes (a home folder whose
   name is not UTF-8, settings/base.py rule 3), and its text's ``encode()`` ended the start in
   a UnicodeEncodeError (review 76). What this module says of the path, its errors and its
   log, spells it by ``shown_path`` (core/text.py).
2. ``stop`` removes the link only while it still points at this pty (another program's link
   put there since is left alone), then closes the pair.
3. A client may close the slave and open it again, as often as it likes: the server keeps its
   own slave descriptor open, so the master never reads EIO while nobody has it open (as
   emulators/pty.py rule 2), and its thread sleeps in poll() (interfaces/fdwait.py) until
   bytes or ``stop`` come.
   An EIO that comes anyway waits EIO_RETRY_S on the stop pipe before the next read: the
   thread never spins.
4. One client at a time is the serial port's nature: one session serves whoever has the slave
   open. A command left unfinished for USEFUL_WITHIN_S is dropped (a fresh session), so what
   a vanished client half sent never prefixes the next one's first line; a session's Close
   starts a fresh session too.
5. A reply nobody reads (no client, or one that does not read) is dropped once the pty's
   buffer is full, counted in ``replies_dropped`` and logged at most once per DROP_LOG_S:
   the server never blocks on a write.
6. What a client left unread is not the next one's: the pty keeps it (rule 3 holds the slave
   open), and a client that does not flush its input on open would read it first (Hamlib's
   GS-232B reads a reply up to its CR and leaves the LF). So what is still unread STALE_S
   after the last reply was written is discarded (counted in ``stale_dropped``): a client
   that asked reads its reply well within that.
7. The pty never echoes: a client may turn the tty's ECHO on (a program opening the port in
   cooked mode, ``stty sane``), and a pty echoes what its master writes back to the master, so
   the server would read its own replies as commands and answer them for ever. A serial line
   has no echo towards the computer: before each reply, ECHO and ECHONL found on are turned
   off again (logged once a server), the client's other settings left as they are.
8. Nothing ends the thread but ``stop`` (docs/architecture.md rule 8): a fault in a session or
   in the loop itself (an ioctl that fails, a bug) is logged with its traceback at most once
   per FAULT_LOG_S, and the server goes on with a fresh session after EIO_RETRY_S; the link
   stays served.
9. A client cannot starve a stop (docs/architecture.md rule 12), as on the TCP ports
   (interfaces/tcplines.py rule 5): a wake-up reads at most tcplines.READ_BYTES (so runs at most
   that many commands), and the pty has a budget of tcplines.RATE_BYTES_S, each reply costing
   tcplines.REPLY_COST more and each wake-up tcplines.READ_COST more; over it, the thread
   sleeps on the stop pipe (in the kernel) and the client's bytes wait in the pty (its writes
   block or fail, as on a serial line), counted in ``paused``.
10. A STOP or lock ON is the last word over every move the client wrote before it, as on the
   TCP ports (interfaces/tcplines.py rule 9, whose Fence and Looks it uses): at each read,
   and right before the rotator counts each halt (its ``halt_watchers``), the rotator's halt
   count is read, then what the client has written so far (read, plus FIONREAD on the
   master); a move is judged against the count of the first look that held its bytes, and
   no read goes past the bytes one look counted. An attack pass: a program wrote 400 targets
   in one burst, the budget (rule 9) left most in the pty, an MQTT STOP stopped the rotor,
   and the 285 read after it were each carried out; a cold review: a target written while
   the thread slept over its budget, before an MQTT STOP, was carried out after it. The looks
   date the bytes as the TCP ports' do (``waited``: the pty held nothing unread before the
   wait its bytes ended), and the fence hands that with each move and stop (front.py rule 3:
   the remote stamps with it; review 24: the remote's GS-232 pty dated nothing, and a move
   written before a STOP from Home Assistant, read after it, turned the rotor). A command
   that keeps a bearing for a later one (the DCU-1's ``AP1``, gs232/ package rule 10) keeps
   with it what the fence says of its own bytes' look, not the count when it is read (attack
   11: ``AP1200;`` written before an MQTT STOP, read after it over the budget, was turned to
   by the ``AM1;`` written after the STOP).
"""

from __future__ import annotations

import errno
import fcntl
import hashlib
import logging
import math
import os
import socket
import struct
import termios
import threading
import time
import tty
from collections.abc import Callable, Sequence
from typing import Protocol

from bridge.core.haltwatch import HaltWatchers
from bridge.core.ratelimit import Budget
from bridge.core.text import shown_path
from bridge.interfaces.fdwait import readable
from bridge.interfaces.tcplines import (
    RATE_BYTES_S,
    READ_BYTES,
    READ_COST,
    REPLY_COST,
    Fence,
    Looks,
)

log = logging.getLogger(__name__)

USEFUL_WITHIN_S = 60.0  # rule 4: an unfinished command is dropped after this
EIO_RETRY_S = 0.2  # rule 3
DROP_LOG_S = 10.0  # rule 5
STALE_S = 2.0  # rule 6
FAULT_LOG_S = 60.0  # rule 8


class PtySession(Protocol):
    """One client's conversation (tcplines.LineSession's shape): bytes in, replies out; a reply
    that is not bytes (tcplines.Close) ends the session."""

    @property
    def idle(self) -> bool: ...

    def feed(self, data: bytes) -> Sequence[object]: ...


class PtyLineServer:
    """One pty for one rotator, linked at ``path``. ``label`` names the front end in logs and
    errors; ``key`` is its settings prefix (``gs232`` for ``gs232_pty``)."""

    def __init__(
        self,
        rotator_id: str,
        path: str | os.PathLike[str],
        session: Callable[[], PtySession],
        *,
        label: str,
        key: str,
        useful_within_s: float = USEFUL_WITHIN_S,
        stale_s: float = STALE_S,
        clock: Callable[[], float] = time.monotonic,
        halt_count: Callable[[], int] | None = None,
        halt_watchers: HaltWatchers | None = None,
    ) -> None:
        """``halt_count`` and ``halt_watchers``: the rotator's (rule 10: the pty is looked at
        right before each halt is counted)."""
        self.rotator_id = rotator_id
        self.label = label
        self.path = os.path.abspath(os.path.expanduser(os.fspath(path)))
        self.shown = shown_path(self.path)  # (rule 1: what it says of the path)
        self._key = key
        self._session = session
        self._useful_within_s = useful_within_s
        self._stale_s = stale_s
        self._clock = clock
        self._master = -1
        self._slave = -1  # our own: rule 3
        self.slave_name = ""
        self._wake_r, self._wake_w = -1, -1
        self._thread: threading.Thread | None = None
        self.wakeups = 0  # select() returns, for the tests (rule 3: no spinning)
        self.faults = 0  # rule 8
        self.paused = 0  # rule 9
        self.replies_dropped = 0
        self.stale_dropped = 0  # bytes (rule 6)
        self._written_s: float | None = None  # when the last reply was written (rule 6)
        self._dropped_logged_s = -DROP_LOG_S
        self._echo_said = False  # rule 7
        self._claim: socket.socket | None = None  # rule 1
        self._looks = Looks()  # rule 10: what the clients have written, read or not
        self._halt_count = halt_count
        self._halt_watchers = halt_watchers if halt_count is not None else None
        self._watcher = self._halt_coming  # (one bound method: removed as it was added)

    @property
    def most_held(self) -> int:
        """Its clients hold no descriptor: one pty, opened at ``listen`` (app.py rule 5)."""
        return 0

    @property
    def address(self) -> str:
        """Where clients open it (the link)."""
        return self.path

    def _error(self, code: int, reason: str) -> OSError:
        return OSError(
            code,
            f"{self.label} for rotator {self.rotator_id!r}: cannot link a pty at "
            f"{self.shown}: "
            f"{reason} (give it another {self._key}_pty)",
        )

    def listen(self) -> None:
        """Rule 1: the pty pair and its link; OSError (one line) if the link cannot be made."""
        if self._master >= 0:
            return
        if os.path.lexists(self.path) and not os.path.islink(self.path):
            raise self._error(errno.EEXIST, "something that is not a link is there")
        self._claim = self._claimed()
        master, slave = os.openpty()
        try:
            tty.setraw(slave)
            os.set_blocking(master, False)
            name = os.ttyname(slave)
            temp = f"{self.path}.{os.getpid()}.tmp"
            try:
                if os.path.lexists(temp):
                    os.unlink(temp)
                os.symlink(name, temp)
                os.replace(temp, self.path)  # a leftover link goes in the same step
            except OSError as exc:
                raise self._error(exc.errno or errno.EIO, exc.strerror or str(exc)) from None
        except BaseException:
            os.close(master)
            os.close(slave)
            self._unclaim()
            raise
        self._master, self._slave, self.slave_name = master, slave, name

    def _claimed(self) -> socket.socket | None:
        """Rule 1: this path claimed for this server's life; OSError if another holds it."""
        key = hashlib.sha256(os.fsencode(self.path)).hexdigest()[:32]  # its bytes: any
        claim = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            claim.bind(f"\0rotor-bridge-pty-{key}")
        except OSError as exc:
            claim.close()
            if exc.errno == errno.EADDRINUSE:
                raise self._error(
                    errno.EADDRINUSE, "another program serves a pty there (a second rotor-bridge?)"
                ) from None
            return None  # no abstract sockets here: no claim, as before
        return claim

    def _unclaim(self) -> None:
        if self._claim is not None:
            self._claim.close()
            self._claim = None

    def start(self) -> None:
        """Link (OSError as ``listen``) and serve in a thread."""
        self.listen()
        self._wake_r, self._wake_w = os.pipe()
        if self._halt_watchers is not None:  # rule 10
            self._halt_watchers.add(self._watcher)
        self._thread = threading.Thread(
            target=self._serve, name=f"{self._key}-pty-{self.rotator_id}", daemon=True
        )
        self._thread.start()
        log.info("%s for %s on %s (%s)", self.label, self.rotator_id, self.shown, self.slave_name)

    def stop(self, timeout_s: float = 3.0) -> None:
        """Rule 2."""
        if self._master < 0:
            return
        if self._halt_watchers is not None:
            self._halt_watchers.remove(self._watcher)
        if self._thread is not None:
            os.write(self._wake_w, b"x")
            self._thread.join(timeout_s)
            self._thread = None
            os.close(self._wake_r)
            os.close(self._wake_w)
        try:
            if os.readlink(self.path) == self.slave_name:
                os.unlink(self.path)
        except OSError:
            pass  # gone already, or not a link any more: not ours to touch
        with self._looks.lock:  # (no halt's look at a descriptor being closed)
            os.close(self._master)
            os.close(self._slave)
            self._master = self._slave = -1
        self._unclaim()

    # -- the thread -------------------------------------------------------------------------
    def _serve(self) -> None:
        """Rule 8: the loop, again after a fault, until ``stop``."""
        logged_s = -math.inf
        while True:
            try:
                self._serve_until_stopped()
                return
            except Exception:
                now = self._clock()
                if now - logged_s >= FAULT_LOG_S:
                    logged_s = now
                    log.exception("%s for %s failed; serving on", self.label, self.rotator_id)
                self.faults += 1
            if readable((self._wake_r,), EIO_RETRY_S):
                return

    def _serve_until_stopped(self) -> None:
        session = self._session()
        with self._looks.lock:
            self._looks.seen.clear()  # rule 10: counted afresh from what waits now
            self._looks.read = 0
        budget = Budget(RATE_BYTES_S, self._clock())
        pending_since: float | None = None
        while True:
            pause_s = budget.wait_s(self._clock())
            if pause_s > 0:  # rule 9: the pty unread until the budget allows
                self.paused += 1
                if readable((self._wake_r,), pause_s):
                    return
                continue
            deadlines = []
            if pending_since is not None:
                deadlines.append(pending_since + self._useful_within_s)
            if self._written_s is not None:
                deadlines.append(self._written_s + self._stale_s)
            timeout = max(0.0, min(deadlines) - self._clock()) if deadlines else None
            waited = not readable((self._master,), 0)  # rule 10: what comes is seen then
            ready = readable((self._master, self._wake_r), timeout)
            self.wakeups += 1
            if self._wake_r in ready:
                return
            if not ready:
                now = self._clock()
                if self._written_s is not None and now >= self._written_s + self._stale_s:
                    self._discard_unread()
                if pending_since is not None and now >= pending_since + self._useful_within_s:
                    log.info(
                        "%s for %s: an unfinished command dropped", self.label, self.rotator_id
                    )
                    fence = getattr(session, "fence", None)
                    session, pending_since = self._session(), None  # rule 4
                    self._carry(fence, session)
                continue
            try:
                fence, data = self._read_looked(session, waited)
            except BlockingIOError:
                continue
            except OSError as exc:
                if exc.errno != errno.EIO:
                    log.warning("%s for %s: %s", self.label, self.rotator_id, exc)
                if readable((self._wake_r,), EIO_RETRY_S):  # rule 3
                    return
                continue
            if not data:
                continue
            replies = session.feed(data)
            for reply in replies:
                if not isinstance(reply, bytes):  # a session's end (tcplines.Close)
                    session = self._session()
                    self._carry(fence, session)
                elif reply:
                    self._write(reply)
            budget.spend(READ_COST + len(data) + REPLY_COST * len(replies), self._clock())
            if session.idle:
                pending_since = None
            elif pending_since is None:
                pending_since = self._clock()

    def _read_looked(self, session: PtySession, waited: bool = False) -> tuple[Fence | None, bytes]:
        """Rule 10: a read, looked at first: the rotator's halt count, then
        what the client has written so far (read, plus what waits in the pty), as one step
        with the read; the read stops at the bytes the oldest look it has not read counted,
        and the session's fence is told that look's count and since when those bytes were
        there (``waited``: nothing was unread before the wait that ended with them; tcplines.py
        ``Looks``). Its fence (None: none) and the bytes."""
        fence: Fence | None = getattr(session, "fence", None)
        looks = self._looks
        with looks.lock:
            if fence is None or fence.count is None:
                data = os.read(self._master, READ_BYTES)
                looks.read += len(data)
                return fence, data
            looked_s = looks.look(
                self._master, fence.count(), waited=waited
            )  # (the count first: a halt between the two errs toward refusing)
            most, arrived, arrived_s = looks.next_read()
            asked = min(most, READ_BYTES)
            data = os.read(self._master, asked)
            if len(data) < asked:
                looks.drained(looked_s)
            looks.read += len(data)
        fence.arrived, fence.arrived_s = arrived, arrived_s
        return fence, data

    def _halt_coming(self) -> None:
        """Rule 10: a halt is about to be counted (core/haltwatch.py): the pty is looked at now,
        at the count before it, so that what the client wrote by then, while the thread sleeps
        over its budget (rule 9), is not taken as written after it."""
        assert self._halt_count is not None
        count = self._halt_count()
        with self._looks.lock:
            if self._master >= 0:
                self._looks.look(self._master, count)

    @staticmethod
    def _carry(fence: Fence | None, session: PtySession) -> None:
        """Rule 10: a fresh session's fence: the halts the old session's own stops made stay
        the client's own."""
        to: Fence | None = getattr(session, "fence", None)
        if fence is not None and to is not None:
            fence.carry(to)

    def _discard_unread(self) -> None:
        """Rule 6."""
        self._written_s = None
        unread = struct.unpack("i", fcntl.ioctl(self._slave, termios.FIONREAD, b"\0" * 4))[0]
        if unread:
            termios.tcflush(self._slave, termios.TCIFLUSH)
            self.stale_dropped += unread

    def _no_echo(self) -> None:
        """Rule 7."""
        attrs = termios.tcgetattr(self._slave)
        echo = termios.ECHO | termios.ECHONL
        if attrs[3] & echo:
            attrs[3] &= ~echo
            termios.tcsetattr(self._slave, termios.TCSANOW, attrs)
            if not self._echo_said:
                self._echo_said = True
                log.warning(
                    "%s for %s: a client turned echo on at %s (it would echo the replies back "
                    "as commands): turned off again",
                    self.label,
                    self.rotator_id,
                    self.shown,
                )

    def _write(self, reply: bytes) -> None:
        """Rule 5: all of it, or what is left dropped; rule 7 first."""
        self._no_echo()
        self._written_s = self._clock()  # rule 6
        view = memoryview(reply)
        while view:
            try:
                view = view[os.write(self._master, view) :]
            except (BlockingIOError, OSError):
                self.replies_dropped += 1
                now = self._clock()
                if now - self._dropped_logged_s >= DROP_LOG_S:
                    self._dropped_logged_s = now
                    log.info(
                        "%s for %s: a reply dropped, nobody reads %s",
                        self.label,
                        self.rotator_id,
                        self.shown,
                    )
                return
