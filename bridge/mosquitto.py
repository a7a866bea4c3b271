"""A private mosquitto process on a loopback port: for the demo and the tests.

The demo starts one only when nothing answers at the configured address. (We tried amqtt as an
embedded broker: 0.12.1 moved the bridge's subscriptions to a later anonymous client's session,
after which the bridge silently received no commands. Debian's mosquitto is what the tests and
production use anyway.)
"""

from __future__ import annotations

import shutil
import signal
import socket
import subprocess
import time
from pathlib import Path


class BrokerError(RuntimeError):
    pass


def find_mosquitto() -> str | None:
    return shutil.which("mosquitto") or next(
        (p for p in ("/usr/sbin/mosquitto", "/usr/local/sbin/mosquitto") if Path(p).exists()), None
    )


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def answers(host: str, port: int, timeout_s: float = 0.5) -> bool:
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            return True
    except OSError:
        return False


class Mosquitto:
    """``start()``/``stop()``/``restart()``; the port stays the same across restarts."""

    def __init__(
        self,
        workdir: Path,
        *,
        port: int | None = None,
        host: str = "127.0.0.1",
        extra_conf: str = "",
    ) -> None:
        exe = find_mosquitto()
        if exe is None:
            raise BrokerError(
                "mosquitto is not installed (Debian/Ubuntu: sudo apt-get install mosquitto)"
            )
        self.exe = exe
        self.host = host
        self._auto_port = port is None
        self.port = port or free_port()
        self.workdir = workdir
        self.conf = workdir / "mosquitto.conf"
        self.log = workdir / "mosquitto.log"
        self.extra_conf = extra_conf
        self.proc: subprocess.Popen[bytes] | None = None

    def start(self, timeout_s: float = 10.0) -> Mosquitto:
        for attempt in range(3):
            try:
                return self._start(timeout_s)
            except BrokerError:
                # a free port can be taken by someone else between finding it and binding it
                # (parallel test workers); an automatically chosen one is simply chosen again
                if not self._auto_port or attempt == 2:
                    raise
                self.port = free_port()
        raise AssertionError("unreachable")

    def _start(self, timeout_s: float) -> Mosquitto:
        self.workdir.mkdir(parents=True, exist_ok=True)
        self.conf.write_text(
            f"listener {self.port} {self.host}\n"
            "persistence false\n"
            f"{self.extra_conf or 'allow_anonymous true'}\n"
        )
        with open(self.log, "ab") as log:
            self.proc = subprocess.Popen(
                [self.exe, "-c", str(self.conf), "-v"], stdout=log, stderr=subprocess.STDOUT
            )
        deadline = time.monotonic() + timeout_s
        while not answers(self.host, self.port, 0.2):
            if self.proc.poll() is not None:
                raise BrokerError(f"mosquitto exited: {self.log.read_text()[-2000:]}")
            if time.monotonic() > deadline:
                self.stop()
                raise BrokerError(f"mosquitto did not listen on {self.host}:{self.port}")
            time.sleep(0.02)
        return self

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None

    def kill(self) -> None:
        """Die without a clean shutdown (a crashed broker)."""
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait()
        self.proc = None

    def pause(self) -> None:
        """Freeze the broker (SIGSTOP): its sockets stay open and the kernel goes on taking
        bytes for it, but nothing is read, answered or delivered (a stalled broker)."""
        if self.proc is not None:
            self.proc.send_signal(signal.SIGSTOP)

    def resume(self) -> None:
        if self.proc is not None:
            self.proc.send_signal(signal.SIGCONT)

    def restart(self) -> None:
        """Same port: clients reconnect to where it was."""
        self.stop()
        self._start(10.0)
