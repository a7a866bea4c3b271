"""Opening a controller's serial port, the way a long-running service must.

Rules:
1. Ports are opened by path, ideally a stable /dev/serial/by-id/... link, so a replugged adapter
   that comes back as another ttyUSB is found again.
2. ``exclusive=True``: two programs on one tty silently steal each other's bytes; a held port is
   a clear "port busy" error instead (pyserial uses flock on POSIX). flock binds only programs
   that ask for it (Hamlib's rotctld does not), so the tty is also set TIOCEXCL: the kernel
   then refuses every later open() of it (but root's) while the bridge has it.
3. Junk already waiting (the 0xE0 power-on byte, a banner) is drained right after opening.
4. Every failure is a PortError with a message a user can act on; nothing here retries or
   sleeps: the worker owns back-off.
5. A port that poll() calls readable but that has no bytes while its device is still there
   has a second reader (one that opened it first, without a lock): "busy", not "unplugged".
   A port gone (a hung-up tty: a read's end of file, or EIO, ENXIO or ENODEV from a read or a
   write) says "(adapter unplugged?)" whichever of them finds it first (``_gone``: a loaded
   CI run's unplug found by the next poll's write said "[Errno 5] Input/output error" alone).
6. Listing the machine's ports (``rotor-bridge ports``) is here too: the engine is the only
   layer that imports pyserial.
6. Reads never wait: a read takes what is there. A write is one short frame or a lost link (a
   stuck line must not hold up every other rotator: lines.py rule 2), with one bounded wait: a
   tty refuses a non-blocking write outright (EAGAIN, nothing taken) while another writer of
   the same tty is inside its own write (the kernel's per-tty write lock: the stop express
   writing its stop frame, interfaces/mqtt/express.py), however much room it has; the tty says
   writable again as that write ends. So a frame the tty takes none or part of is finished as
   soon as the tty is writable, for up to WRITE_WAIT_S; a tty that stays unwritable that long,
   or that holds FULL_BYTES or more still to send when it refuses (a full buffer: the adapter
   is stuck; it says writable only under 256, most of a second away or more at a rotor's baud
   rate), is a lost link at once, and no frame is left cut short for the next one to land in
   while it can still be finished. A rotor's frames never queue that many.
7. A PortWatch (the stop express, interfaces/mqtt/express.py) is told an opened port's descriptor on
   the thread that opened it, and that it (its descriptor) is going before it is closed, on the
   thread that closes it (``watched``, ``close_in_background``): a copy of the descriptor held
   elsewhere keeps the tty open, and TIOCEXCL (rule 2) would then refuse the reopen. A watch
   that fails costs the port nothing (logged).
"""

from __future__ import annotations

import errno
import fcntl
import logging
import math
import os
import select
import sys
import termios
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, TypeAlias

import serial
from serial.tools import list_ports

from bridge.core.text import shown_path
from bridge.protocols.base import ModelSpec


class PortError(Exception):
    pass


# rule 6: how long a write waits for a tty that refused it (another writer inside its own
# write holds the tty for microseconds, a descheduled one for a few scheduler slices). A stuck
# adapter costs every other line this wait once per reconnect, so it stays short: the tty is
# tried again after every wake, so this thread's own lateness under load is no refusal.
WRITE_WAIT_S = 0.05
# rule 6: a tty holding this many bytes is full, not taken by another writer: it says writable
# again only under 256 queued bytes, 768 bytes away (1.6 s at 4800 baud: a stuck adapter)
FULL_BYTES = 1024


# what opens a port: open_port, or a test's stand-in (path, spec, baud or the model's)
PortOpener: TypeAlias = Callable[[str, ModelSpec, int | None], serial.Serial]
log = logging.getLogger(__name__)


class PortWatch(Protocol):
    """Rule 7: told of each port of one rotator, on the short-lived open and close threads."""

    def opened(self, fd: int) -> None: ...

    def closing(self, fd: int) -> None: ...


def watched(opener: PortOpener, watch: PortWatch) -> PortOpener:
    """``opener``, and the watch told the descriptor of each port it opens (rule 7)."""

    def open_watched(path: str, spec: ModelSpec, baud: int | None) -> serial.Serial:
        port = opener(path, spec, baud)
        try:
            watch.opened(port.fileno())
        except Exception:
            log.exception(
                "%s: the port's watch failed (the port is open all the same)", shown_path(path)
            )
        return port

    return open_watched


_PARITY = {"N": serial.PARITY_NONE, "E": serial.PARITY_EVEN, "O": serial.PARITY_ODD}


def open_port(path: str, spec: ModelSpec, baud: int | None = None) -> serial.Serial:
    try:
        port = serial.Serial(
            port=None,
            baudrate=baud or spec.baud,
            bytesize=spec.bytesize,
            parity=_PARITY[spec.parity],
            stopbits=spec.stopbits,
            timeout=0,  # the lines thread polls the fd; the worker reads what is there
            xonxoff=False,
            rtscts=False,
            dsrdtr=False,
            exclusive=True,
        )
        port.port = path
        port.open()
    except serial.SerialException as exc:
        raise PortError(_explain(path, exc)) from None
    except (OSError, ValueError, termios.error) as exc:  # termios.error is no OSError
        raise PortError(shown_path(f"cannot open {path}: {exc}")) from None
    try:
        port.reset_input_buffer()
        fcntl.ioctl(port.fileno(), termios.TIOCEXCL)  # rule 2: no later open() either
    except (serial.SerialException, OSError, termios.error) as exc:
        port.close()
        raise PortError(shown_path(f"cannot flush {path}: {exc}")) from None
    return port


def _explain(path: str, exc: serial.SerialException) -> str:
    """Why ``path`` did not open, as the bridge says it: pyserial's text names the path too,
    so all of it is spelled as ``shown_path`` spells a path (core/text.py)."""
    return shown_path(_why(path, exc))


def _why(path: str, exc: serial.SerialException) -> str:
    text = str(exc)
    err = getattr(exc, "errno", None)
    if err == errno.ENOENT or (not os.path.exists(path) and "No such file" in text):
        return f"{path} does not exist (adapter unplugged? see `rotor-bridge ports`)"
    if err == errno.EACCES or "Permission denied" in text:
        return f"no permission to open {path} (add the user to the 'dialout' group)"
    if "exclusively lock" in text or err in (errno.EAGAIN, errno.EWOULDBLOCK):
        return f"{path} is busy: another program holds it (rotctld, another bridge?)"
    return f"cannot open {path}: {text}"


BY_ID_DIR = "/dev/serial/by-id"


@dataclass(frozen=True)
class PortInfo:
    device: str
    stable_path: str | None  # the /dev/serial/by-id link to it (rule 1), if there is one
    description: str
    vid: int | None
    pid: int | None
    serial_number: str | None


def list_serial_ports() -> list[PortInfo]:
    """The machine's serial ports, sorted by device path (rule 5)."""
    by_id: dict[str, str] = {}
    if os.path.isdir(BY_ID_DIR):
        for name in sorted(os.listdir(BY_ID_DIR)):
            link = os.path.join(BY_ID_DIR, name)
            by_id[os.path.realpath(link)] = link
    return [
        PortInfo(
            device=p.device,
            stable_path=by_id.get(os.path.realpath(p.device)),
            description=p.description,
            vid=p.vid,
            pid=p.pid,
            serial_number=p.serial_number,
        )
        for p in sorted(list_ports.comports(), key=lambda p: p.device)
    ]


def close_quietly(port: serial.Serial) -> None:
    try:
        port.close()
    except Exception:  # closing a yanked port may fail too
        pass


def close_watched(port: serial.Serial, watch: PortWatch | None) -> None:
    """The watch told (rule 7), then the port closed."""
    if watch is not None:
        try:
            watch.closing(port.fileno())
        except Exception:
            log.exception("the port's watch failed (the port is closed all the same)")
    close_quietly(port)


def close_in_background(port: serial.Serial, watch: PortWatch | None = None) -> threading.Thread:
    """Close a port on a thread of its own, returned to be waited for where waiting is fine: a
    tty with unsent output waits for it to drain (up to 30 s on a USB adapter), and the lines
    thread may not wait for that. ``watch`` is told first (rule 7)."""

    closing = threading.Thread(
        target=close_watched, args=(port, watch), name="close port", daemon=True
    )
    closing.start()
    return closing


class PendingOpen:
    """One attempt to open a port, on a thread of its own (a wedged USB adapter can hold open()
    for seconds, or for good); ``wake`` is called when ``result`` (the port, or the exception)
    is there. Abandoned (the rotator stops meanwhile, or the open outlasts worker.py's
    OPEN_BOUND_S), a port opened too late is closed at once; ``running`` says whether its
    open() has returned yet (worker.py rule 4: each abandoned attempt still running doubles
    the next one's bound)."""

    def __init__(self, attempt: Callable[[], serial.Serial], wake: Callable[[], None]) -> None:
        self.result: serial.Serial | Exception | None = None
        self._lock = threading.Lock()
        self._abandoned = False
        self._watch: PortWatch | None = None  # abandon's, told before a late port is closed
        self._thread = threading.Thread(
            target=self._run, args=(attempt, wake), name="open port", daemon=True
        )
        self._thread.start()

    @property
    def running(self) -> bool:
        """Whether the attempt is still inside its open(), abandoned or not."""
        return self._thread.is_alive()

    def _run(self, attempt: Callable[[], serial.Serial], wake: Callable[[], None]) -> None:
        try:
            result: serial.Serial | Exception = attempt()
        except Exception as exc:
            result = exc
        with self._lock:
            if self._abandoned:
                if isinstance(result, serial.Serial):
                    close_watched(result, self._watch)
                return
            self.result = result
        wake()

    def abandon(self, watch: PortWatch | None = None) -> threading.Thread | None:
        """Give the attempt up; a port it already opened is closed in the background (the
        thread closing it is returned; ``watch`` told first, rule 7)."""
        with self._lock:
            self._abandoned = True
            self._watch = watch
            if isinstance(self.result, serial.Serial):
                return close_in_background(self.result, watch)
        return None


_GONE_ERRNOS = frozenset({errno.EIO, errno.ENXIO, errno.ENODEV})  # rule 5: a hung-up tty


def _gone(exc: OSError, what: str) -> OSError:
    """Rule 5: a read's or write's error on a port that is gone, as one that says so (else
    ``exc`` as it was)."""
    if exc.errno not in _GONE_ERRNOS:
        return exc
    return serial.SerialException(f"port {what} failed: {exc.strerror} (adapter unplugged?)")


def read_available(fd: int, readable: bool, path: str | None = None) -> bytes:
    """Everything the port has now. ``readable``: poll said so (else a reply is due: worker.py
    rule 2). A tty set to return at once (VMIN 0) reads b"" when it has nothing: only after
    poll said it was readable does that mean the adapter is gone, or (rule 5), while the
    device is still there, that another program took the bytes."""
    try:
        data = os.read(fd, 4096)
    except BlockingIOError:
        return b""
    except OSError as exc:
        raise _gone(exc, "read") from exc
    if not data and readable:
        if path is not None and os.path.exists(path):
            raise serial.SerialException(
                f"{shown_path(path)} is busy: readable but the bytes were gone, while the "
                "adapter is there: another program reads from this port (Hamlib's rotctld, another "
                "bridge?); stop it"
            )
        raise serial.SerialException("port readable but no data (adapter unplugged?)")
    return data


def queued(fd: int) -> int:
    """Bytes the tty still holds to send (TIOCOUTQ), 0 if it cannot say (not a tty)."""
    try:
        answer = fcntl.ioctl(fd, termios.TIOCOUTQ, b"\0\0\0\0")
    except OSError:
        return 0
    return int.from_bytes(answer, sys.byteorder, signed=True)


def write_frame(port: serial.Serial, data: bytes) -> None:
    """A short frame written whole: one write() as a rule. A tty that takes none or part of it
    (another writer of the tty inside its write, or a full buffer) is waited for, up to
    WRITE_WAIT_S, and the rest written; one still unwritable then is a lost link: the line is
    stuck, and waiting longer would hold up every other rotator's line (rule 6)."""
    fd = port.fileno()
    rest, deadline = data, None
    while True:
        try:
            rest = rest[os.write(fd, rest) :]
        except BlockingIOError:
            pass
        except OSError as exc:
            raise _gone(exc, "write") from exc
        if not rest:
            return
        if deadline is None and queued(fd) >= FULL_BYTES:
            break  # a full buffer, not another writer: it drains for seconds, if ever (rule 6)
        now = time.monotonic()
        deadline = now + WRITE_WAIT_S if deadline is None else deadline
        if now >= deadline:
            break
        waiting = select.poll()  # not select(): a busy bridge's descriptors pass 1023
        waiting.register(fd, select.POLLOUT)
        events = waiting.poll(max(1, math.ceil((deadline - now) * 1000)))
        if events and not events[0][1] & select.POLLOUT:
            break  # an error or a hang-up, not room: no use waiting for it
    raise serial.SerialException("the port takes no more bytes (adapter stuck?)")
