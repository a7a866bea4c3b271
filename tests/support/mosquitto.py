"""The tests' mosquitto: the demo's private broker (bridge/demo/mosquitto.py) with what only tests
ask of a broker: a configuration of their own (ACLs, TLS, bridges between brokers), another free
port when a parallel worker took the one chosen, a crash, a freeze and a restart on the same
port. Its start's deadline scales with the machine (waiting.py rule 1)."""

from __future__ import annotations

import signal
from pathlib import Path
from typing import Self

from bridge.demo.mosquitto import BrokerError, answers, find_mosquitto, listens
from bridge.demo.mosquitto import Mosquitto as DemoMosquitto
from tests.support.ports import free_port
from tests.support.waiting import slow

__all__ = ["BrokerError", "Mosquitto", "answers", "find_mosquitto", "free_port", "listens"]


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
