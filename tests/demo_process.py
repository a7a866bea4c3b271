"""`rotor-bridge demo` as a user runs it: a subprocess whose printed lines the test reads (the
topics to use are whatever it prints), optionally with a terminal as its stdin to type into."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

BASE_LINE = re.compile(r"watch: mosquitto_sub (?:-h \S+ -p \d+ )?-t '([^']+)/#' -v")


class DemoProcess:
    def __init__(
        self,
        args: list[str],
        tmpdir: Path,
        *,
        terminal: bool = False,
        env: dict[str, str] | None = None,
    ) -> None:
        """Start it with TMPDIR=`tmpdir` (so what it leaves behind can be seen) and, when
        `terminal`, a pseudo-terminal as stdin (it reads typed lines only from a terminal)."""
        tmpdir.mkdir(parents=True, exist_ok=True)
        environ = {k: v for k, v in os.environ.items() if not k.startswith("ROTOR_BRIDGE_")}
        environ.update(env or {}, TMPDIR=str(tmpdir))
        self._master: int | None = None
        stdin: int = subprocess.DEVNULL
        if terminal:
            self._master, stdin = os.openpty()
        self.lines: list[str] = []
        self._cond = threading.Condition()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "bridge", "demo", *args],
            stdin=stdin,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            env=environ,
        )
        if terminal:
            os.close(stdin)
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

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
        deadline = time.monotonic() + timeout_s
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
        rc = self.proc.wait(timeout_s)
        self._reader.join(5)
        return rc

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(15)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        if self._master is not None:
            os.close(self._master)
            self._master = None
