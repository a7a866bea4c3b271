"""`rotor-bridge demo` as a user runs it: a subprocess whose printed lines the test reads (the
topics to use are whatever it prints), optionally with a terminal as its stdin to type into, or
(``screen``) a terminal as both its stdin and its stdout, as in a terminal window."""

from __future__ import annotations

import fcntl
import os
import re
import struct
import subprocess
import sys
import termios
import threading
import time
from pathlib import Path

from bridge import demo
from bridge.cli import build_parser
from tests.support.mosquitto import free_port
from tests.support.waiting import slow

BASE_LINE = re.compile(r"watch: mosquitto_sub (?:-h \S+ -p \d+ )?-t '([^']+)/#' -v")


class DemoProcess:
    def __init__(
        self,
        args: list[str],
        tmpdir: Path,
        *,
        terminal: bool = False,
        screen: bool = False,
        env: dict[str, str] | None = None,
        group: bool = False,
    ) -> None:
        """Start it with TMPDIR=`tmpdir` (so what it leaves behind can be seen) and, when
        `terminal`, a pseudo-terminal as stdin (it reads typed lines only from a terminal); when
        `screen`, as stdout too (``screen_text``: every character it wrote there); when
        `group`, in a process group of its own (a signal to it reaches its children too, as a
        terminal's Ctrl-C does)."""
        tmpdir.mkdir(parents=True, exist_ok=True)
        environ = {k: v for k, v in os.environ.items() if not k.startswith("ROTOR_BRIDGE_")}
        environ.update(env or {}, TMPDIR=str(tmpdir))
        self._master: int | None = None
        stdin: int = subprocess.DEVNULL
        if terminal or screen:
            self._master, stdin = os.openpty()
            fcntl.ioctl(stdin, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))
        self.lines: list[str] = []
        self.screen_text = ""
        self._cond = threading.Condition()
        self.proc = subprocess.Popen(
            # a console port of its own: demos started at once by parallel tests would race for
            # the default one (a user's second demo finds it taken and takes another)
            [sys.executable, "-m", "bridge", "demo", *_web_port(args), *args],
            stdin=stdin,
            stdout=stdin if screen else subprocess.PIPE,
            stderr=stdin if screen else subprocess.STDOUT,
            env=environ,
            process_group=0 if group else None,
        )
        if self._master is not None:
            self.tty = stdin  # the terminal's own side, kept open: its settings can be read
        self._reader = threading.Thread(target=self._read_screen if screen else self._read)
        self._reader.daemon = True
        self._reader.start()

    def _read_screen(self) -> None:
        assert self._master is not None
        while True:
            try:
                chunk = os.read(self._master, 4096)
            except OSError:  # the terminal's other side is gone
                chunk = b""
            with self._cond:
                if not chunk:
                    self._cond.notify_all()
                    return
                self.screen_text += chunk.decode("utf-8", "replace")
                self.lines = self.screen_text.replace("\r\n", "\n").split("\n")
                self._cond.notify_all()

    def wait_screen(self, pattern: str, timeout_s: float = 20.0, start: int = 0) -> re.Match[str]:
        """The first match of `pattern` in what was written to the terminal (from `start`)."""
        rx = re.compile(pattern)
        deadline = time.monotonic() + slow(timeout_s)
        with self._cond:
            while (m := rx.search(self.screen_text, start)) is None:
                left = deadline - time.monotonic()
                if left <= 0 or self.proc.poll() is not None:
                    raise AssertionError(f"never on screen {pattern!r}:\n{self.screen_text!r}")
                self._cond.wait(min(left, 0.5))
            return m

    def keys(self, text: str) -> int:
        """Type `text` without an Enter; how much was on the screen before (for wait_screen)."""
        assert self._master is not None, "started without a terminal"
        with self._cond:
            seen = len(self.screen_text)
        os.write(self._master, text.encode())
        return seen

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for raw in self.proc.stdout:
            with self._cond:
                self.lines.append(raw.decode("utf-8", "replace").rstrip("\n"))
                self._cond.notify_all()

    @property
    def output(self) -> str:
        with self._cond:
            return "\n".join(self.lines)

    def wait_line(self, pattern: str, timeout_s: float = 20.0, start: int = 0) -> re.Match[str]:
        """The first printed line (from line number `start` on) that matches `pattern`."""
        rx = re.compile(pattern)
        deadline = time.monotonic() + slow(timeout_s)
        with self._cond:
            while True:
                for line in self.lines[start:]:
                    m = rx.search(line)
                    if m:
                        return m
                left = deadline - time.monotonic()
                if left <= 0 or (self.proc.poll() is not None and not self._reader.is_alive()):
                    raise AssertionError(
                        f"demo never printed {pattern!r}; it printed:\n{self.output}"
                    )
                self._cond.wait(min(left, 0.5))

    def base_topic(self) -> str:
        """The base topic the demo prints in its `mosquitto_sub` line."""
        return self.wait_line(BASE_LINE.pattern).group(1)

    def type(self, line: str) -> int:
        """Type a line at its terminal; the number of lines printed so far (for wait_line)."""
        assert self._master is not None, "started without a terminal"
        with self._cond:
            seen = len(self.lines)
        os.write(self._master, line.encode() + b"\n")
        return seen

    def wait(self, timeout_s: float) -> int:
        rc = self.proc.wait(timeout_s)  # a deadline the caller scales, as Popen.wait's
        self._reader.join(slow(5))
        return rc

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(slow(15))
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        if self._master is not None:
            os.close(self._master)
            os.close(self.tty)
            self._master = None


def _web_port(args: tuple[str, ...] | list[str]) -> list[str]:
    if any(a.startswith("--web-port") for a in args) or "--help" in args:
        return []
    return ["--web-port", str(free_port())]


def run_demo_in_process(port: int, *flags: str) -> int:
    """``rotor-bridge demo --mqtt-port port --web-port 0 flags...`` run in this process (its
    printed lines in the test's capsys, its log in caplog): its exit code."""
    args = build_parser().parse_args(["demo", "--mqtt-port", str(port), "--web-port", "0", *flags])
    return demo.run(args)
