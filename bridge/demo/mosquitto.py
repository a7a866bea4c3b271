"""The demo's private mosquitto: a broker process on a loopback port, started only when nothing
answers at the demo's MQTT address, stopped with the demo. (The tests' broker,
tests/support/mosquitto.py, is this one with what only tests need: a configuration of their own,
a crash, a freeze, a restart.)

(We tried amqtt as an embedded broker: 0.12.1 moved the bridge's subscriptions to a later
anonymous client's session, after which the bridge silently received no commands. Debian's
mosquitto is what the tests and production use anyway.)

Started means this broker listens: its log (``-v``) says it runs, which it says only once every
listener is bound. Another program on the port answers too, before mosquitto has even tried
to bind it; mosquitto then exits ("Address already in use") and every client would reach the
other program's broker instead (under parallel tests: another test's, which this one's
freezing and restarting then never touch).

The demo's broker dies with the demo (``dies_with_parent``), however the demo ends: a demo killed
with SIGKILL, or by the out-of-memory killer, runs no clean-up, and its broker ran on for good,
answering on the port, where the next demo took it for the user's own broker. The kernel sends
it SIGTERM when the thread that started it ends (``PR_SET_PDEATHSIG``, set between fork and
exec; the demo starts it from its main thread, before it starts any other thread). The kernel
forgets that signal when a process changes its user, as mosquitto started by root does (to the
user ``mosquitto``, unless told ``user root``): run as root, its configuration says ``user root``;
run by anyone else it never changes user. It listens on the loopback address only.

A broker answers (``answers``) when a CONNECT gets a CONNACK within the time the bridge gives
one (CONNACK_TIMEOUT_S): a program that only takes connections (``listens``) may speak no MQTT
at all, and a demo bridged to it would run dead.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import re
import shutil
import signal
import socket
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import Self

from bridge.interfaces.mqtt.paho_client import CONNACK_TIMEOUT_S


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


def listens(host: str, port: int, timeout_s: float = 0.5) -> bool:
    """Whether something takes connections at host:port (any program: see ``answers``)."""
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            return True
    except OSError:
        return False


# MQTT 3.1.1 CONNECT (every broker speaks 3.1.1): a clean session, keep-alive 10 s, an empty
# client id (the broker makes one up)
_CONNECT = bytes([0x10, 12, 0, 4]) + b"MQTT" + bytes([4, 0x02, 0, 10, 0, 0])
_CONNACK = 0x20
_DISCONNECT = bytes([0xE0, 0])


def answers(host: str, port: int, timeout_s: float = CONNACK_TIMEOUT_S) -> bool:
    """Whether an MQTT broker answers at host:port: a CONNECT gets a CONNACK within
    ``timeout_s``, as long as the bridge waits for one (paho_client.py rule 5: a broker slower
    than the demo's look but quicker than that serves the bridge, review 122). A program that
    takes connections and says nothing, or something else than MQTT (a hung broker, an SSH
    tunnel whose far end is gone, a web server), is no broker: the demo would run dead on it."""
    deadline = time.monotonic() + timeout_s
    try:
        with socket.create_connection((host, port), timeout=timeout_s) as s:
            s.sendall(_CONNECT)
            connack = b""  # fixed header (type, length 2), flags, return code
            while len(connack) < 4:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                s.settimeout(left)
                chunk = s.recv(4 - len(connack))
                if not chunk:  # closed without a CONNACK
                    return False
                connack += chunk
                if not bytes([_CONNACK, 2]).startswith(connack[:2]):
                    return False
            with contextlib.suppress(OSError):
                s.sendall(_DISCONNECT)
            return True
    except OSError:
        return False


_RUNNING = re.compile(rb"mosquitto version \S+ running")  # said once every listener is bound

_PR_SET_PDEATHSIG = 1  # linux/prctl.h


def _dies_with_this_thread() -> Callable[[], None] | None:
    """A child's step before exec: SIGTERM when the thread that forks it ends (None where the
    system has no ``prctl``). Everything it needs is looked up here, before the fork: the child
    only calls it."""
    prctl = getattr(ctypes.CDLL(None, use_errno=True), "prctl", None)
    if prctl is None:
        return None
    parent = os.getpid()

    def before_exec() -> None:
        prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
        if os.getppid() != parent:  # the parent died before the signal was asked for
            os._exit(1)

    return before_exec


class Mosquitto:
    """``start()``/``stop()``; a free port unless one is given."""

    def __init__(
        self,
        workdir: Path,
        *,
        port: int | None = None,
        host: str = "127.0.0.1",
        dies_with_parent: bool = False,
    ) -> None:
        exe = find_mosquitto()
        if exe is None:
            raise BrokerError(
                "mosquitto is not installed (Debian/Ubuntu: sudo apt-get install mosquitto)"
            )
        self.exe = exe
        self.host = host
        self.port = port or free_port()
        self.workdir = workdir
        self.conf = workdir / "mosquitto.conf"
        self.log = workdir / "mosquitto.log"
        self.dies_with_parent = dies_with_parent
        self.proc: subprocess.Popen[bytes] | None = None

    def config(self) -> str:
        """mosquitto.conf: one listener, nothing kept, anyone may connect (the demo's own); run
        as root and dying with its parent, it stays root (the kernel's death signal would be
        forgotten as it changed user)."""
        root = "user root\n" if self.dies_with_parent and os.geteuid() == 0 else ""
        return f"listener {self.port} {self.host}\npersistence false\nallow_anonymous true\n{root}"

    def start(self, timeout_s: float = 10.0) -> Self:
        self.workdir.mkdir(parents=True, exist_ok=True)
        self.conf.write_text(self.config())
        with open(self.log, "ab") as log:
            logged = log.tell()  # (the log of an earlier start on the same path stays before it)
            self.proc = subprocess.Popen(  # noqa: PLW1509 (no other thread runs yet: see above)
                [self.exe, "-c", str(self.conf), "-v"],
                stdout=log,
                stderr=subprocess.STDOUT,
                preexec_fn=_dies_with_this_thread() if self.dies_with_parent else None,
            )
        deadline = time.monotonic() + timeout_s
        while not (self._running(logged) and listens(self.host, self.port, 0.2)):
            if self.proc.poll() is not None:
                raise BrokerError(f"mosquitto exited: {self.log.read_text()[-2000:]}")
            if time.monotonic() > deadline:
                self.stop()
                raise BrokerError(f"mosquitto did not listen on {self.host}:{self.port}")
            time.sleep(0.02)
        return self

    def _running(self, logged: int) -> bool:
        """Whether the log since ``logged`` says mosquitto runs: all its listeners are bound."""
        with open(self.log, "rb") as log:
            log.seek(logged)
            return _RUNNING.search(log.read()) is not None

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None
