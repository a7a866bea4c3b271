"""The tests' mosquitto: the demo's private broker (bridge/demo/mosquitto.py) with what only tests
ask of a broker: a configuration of their own (ACLs, TLS, bridges between brokers), another free
port when a parallel worker took the one chosen, a crash, a freeze and a restart on the same
port. Its start's deadline scales with the machine (waiting.py rule 1)."""

from __future__ import annotations

import os
import random
import signal
import socket
from pathlib import Path
from typing import Self

from bridge.demo.mosquitto import BrokerError, answers, find_mosquitto
from bridge.demo.mosquitto import Mosquitto as DemoMosquitto
from tests.support.waiting import slow

__all__ = ["BrokerError", "Mosquitto", "answers", "find_mosquitto", "free_port"]

_PICK = random.SystemRandom()


def _ephemeral_low() -> int:
    try:
        with open("/proc/sys/net/ipv4/ip_local_port_range") as f:
            return int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return 32768


def _own_range() -> range:
    """This process's share of the ports below the kernel's range for outgoing connections:
    one slice per parallel worker (``PYTEST_XDIST_WORKER`` gwN of
    ``PYTEST_XDIST_WORKER_COUNT``), so that two workers never pick the same port (they did:
    both found it free, and the second to listen failed, once in eight CI runs)."""
    low, top = 10_000, _ephemeral_low()
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    try:
        index, count = int(worker.removeprefix("gw")), int(os.environ["PYTEST_XDIST_WORKER_COUNT"])
    except (KeyError, ValueError):
        return range(low, top)
    if not 0 <= index < count or top - low < 100 * count:
        return range(low, top)
    share = (top - low) // count
    return range(low + index * share, low + (index + 1) * share)


_HANDED: set[int] = set()  # the ports this process picked: not picked twice, bound or not


def free_port() -> int:
    """A loopback port free now, below the kernel's range for outgoing connections (a port the
    kernel hands out, bind to 0, is one any test's outgoing connection may take before the test
    listens on it, which a busy parallel suite does; one below that range only a listener can
    take), from this worker's own share (``_own_range``) and never one it picked before."""
    ports = _own_range()
    for _ in range(200):
        port = _PICK.choice(ports)
        if port in _HANDED:
            continue
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
        _HANDED.add(port)
        return port
    with socket.socket() as s:  # a crowded range: the kernel's choice
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Mosquitto(DemoMosquitto):
    """``start()``/``stop()``/``restart()``; the port stays the same across restarts."""

    def __init__(
        self,
        workdir: Path,
        *,
        port: int | None = None,
        host: str = "127.0.0.1",
        extra_conf: str = "",
    ) -> None:
        super().__init__(workdir, port=port or free_port(), host=host)
        self._auto_port = port is None
        self.extra_conf = extra_conf

    def config(self) -> str:
        return (
            f"listener {self.port} {self.host}\npersistence false\n"
            f"{self.extra_conf or 'allow_anonymous true'}\n"
        )

    def start(self, timeout_s: float = 10.0) -> Self:
        for attempt in range(3):
            try:
                return super().start(slow(timeout_s))
            except BrokerError:
                # a free port can be taken by someone else between finding it and binding it
                # (parallel test workers); an automatically chosen one is simply chosen again
                if not self._auto_port or attempt == 2:
                    raise
                self.port = free_port()
        raise AssertionError("unreachable")

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

    def reload(self) -> None:
        """Read the configuration's files again (SIGHUP: mosquitto reloads its ACL file and
        keeps every connection)."""
        if self.proc is not None:
            self.proc.send_signal(signal.SIGHUP)

    def restart(self) -> None:
        """Same port: clients reconnect to where it was."""
        self.stop()
        super().start(slow(10.0))
