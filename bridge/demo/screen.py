"""The demo's terminal: what its console prints, and the lines the user types.

On a terminal the rotators' bearing, elevation and state stay on one status line at the bottom,
redrawn in place, with the line being typed after it; everything else (commands' answers, errors,
the bridge's own log) is printed above it. A bearing that changes every degree so never scrolls
away what the user types.

Rules:
1. Live only when stdout is a terminal (``for_terminal``). Elsewhere (a pipe, a file, the tests)
   every log line is printed as it comes and the status line is never drawn: what a test reads
   is what a user piping the demo reads.
2. Live with a terminal as stdin too, stdin is in cbreak mode (no echo and no line editing by
   the kernel: the screen echoes and edits the typed line itself; ^C stays a signal), put back by
   ``close`` on every way out. The logging handlers that wrote to the terminal write above the
   status line until then.
3. The status line is cut to the terminal's width: a carriage return and an erase always clear
   all of it (a wrapped line could not be).
4. One lock around every write: the MQTT thread, the input thread and logging all print.
"""

from __future__ import annotations

import contextlib
import logging
import os
import shutil
import sys
import termios
import threading
import tty
from collections.abc import Callable
from typing import Any, TextIO

CLEAR_LINE = "\r\x1b[K"  # back to the start of the line, erase to its end
_ERASE = ("\x7f", "\x08")
_KILL_LINE = "\x15"  # ^U
_END = "\x04"  # ^D


class Screen:
    def __init__(self, out: TextIO | None = None, *, live: bool = False) -> None:
        self._out = out or sys.stdout
        self.live = live
        self._started = False
        self._lock = threading.RLock()
        self._fields: dict[str, dict[str, str]] = {}
        self._typed = ""
        self._saved_tty: list[Any] | None = None
        self._saved_streams: list[tuple[logging.StreamHandler[TextIO], TextIO]] = []

    @classmethod
    def for_terminal(cls) -> Screen:
        """Live when stdout is a terminal (rule 1)."""
        return cls(live=sys.stdout.isatty())

    # -- output -------------------------------------------------------------------------------
    def log(self, text: str, *, quiet: bool = False) -> None:
        """A line (or several) above the status line; ``quiet`` ones only when not live (their
        news is on the status line)."""
        with self._lock:
            if not self._drawing():
                if not quiet or not self.live:
                    print(text, file=self._out, flush=True)
                return
            if quiet:
                return
            self._out.write(CLEAR_LINE + text + "\n")  # the terminal adds the \r (ONLCR)
            self._draw()

    def status(self, root: str, leaf: str, text: str) -> None:
        """``leaf`` (bearing, elevation, state) of the rotator at ``root`` is now ``text``."""
        with self._lock:
            self._fields.setdefault(root, {})[leaf] = text
            if self._drawing():
                self._draw()

    def status_text(self) -> str:
        parts = []
        for root, f in self._fields.items():
            name = root.rsplit("/", 1)[-1] if len(self._fields) > 1 else root
            where = " ".join(
                f"{label} {f[leaf]}" for label, leaf in (("az", "bearing"), ("el", "elevation"))
                if leaf in f
            )  # fmt: skip
            parts.append(" ".join(p for p in (name, where, f.get("state", "")) if p))
        return " | ".join(parts)

    def _drawing(self) -> bool:
        return self.live and self._started

    def _draw(self) -> None:
        width = shutil.get_terminal_size((80, 24)).columns - 1
        prompt = f" > {self._typed}" if self._saved_tty is not None else ""  # typing here?
        head = self.status_text()[: max(0, width - len(prompt))]
        self._out.write(CLEAR_LINE + (head + prompt)[-width:])
        self._out.flush()

    # -- live mode ----------------------------------------------------------------------------
    def start(self) -> None:
        """Begin drawing the status line (live only): stdin in cbreak mode, the terminal's
        logging above the status line (rule 2)."""
        if not self.live or self._started:
            return
        if sys.stdin.isatty():
            fd = sys.stdin.fileno()
            self._saved_tty = termios.tcgetattr(fd)
            tty.setcbreak(fd)
        for handler in logging.getLogger().handlers:
            if isinstance(handler, logging.StreamHandler) and handler.stream in (
                sys.stderr,
                sys.stdout,
            ):
                self._saved_streams.append((handler, handler.stream))
                handler.setStream(_Above(self))
        with self._lock:
            self._started = True
            self._draw()

    def close(self) -> None:
        """Erase the status line, put the terminal and the logging back (rule 2)."""
        with self._lock:
            if not self._started:
                return
            self._started = False
            self._out.write(CLEAR_LINE)
            self._out.flush()
        for handler, stream in self._saved_streams:
            handler.setStream(stream)
        self._saved_streams.clear()
        if self._saved_tty is not None:
            with contextlib.suppress(termios.error, OSError):
                termios.tcsetattr(sys.stdin.fileno(), termios.TCSADRAIN, self._saved_tty)
            self._saved_tty = None

    # -- input --------------------------------------------------------------------------------
    def read_lines(self, handle: Callable[[str], bool]) -> None:
        """Hand every typed line to ``handle`` until it returns False or input ends (^D)."""
        if self._saved_tty is None:  # the kernel edits the line and echoes it
            for line in sys.stdin:
                if not handle(line):
                    return
            return
        fd = sys.stdin.fileno()
        escape = False
        while True:
            try:
                chunk = os.read(fd, 64).decode("utf-8", "replace")
            except OSError:
                return
            if not chunk:
                return
            for ch in chunk:
                if escape:  # an arrow or function key: ESC [ ... final letter or ~
                    escape = not (ch.isalpha() or ch == "~")
                    continue
                if ch == "\x1b":
                    escape = True
                elif ch in "\r\n":
                    with self._lock:
                        line, self._typed = self._typed, ""
                        self.log(f"> {line}")
                    if not handle(line):
                        return
                elif ch == _END and not self._typed:
                    return
                else:
                    self._edit(ch)

    def _edit(self, ch: str) -> None:
        with self._lock:
            if ch in _ERASE:
                self._typed = self._typed[:-1]
            elif ch == _KILL_LINE:
                self._typed = ""
            elif ch.isprintable():
                self._typed += ch
            else:
                return
            if self._drawing():
                self._draw()


class _Above:
    """A stream for logging handlers: each complete line goes above the status line."""

    def __init__(self, screen: Screen) -> None:
        self._screen = screen
        self._pending = ""

    def write(self, text: str) -> int:
        self._pending += text
        *lines, self._pending = self._pending.split("\n")
        for line in lines:
            self._screen.log(line)
        return len(text)

    def flush(self) -> None:
        pass
