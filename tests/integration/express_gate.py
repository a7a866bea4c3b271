"""Set-up shared by the express-gating tests (the STOP read by the express while its words are
dropped: test_stop_before_the_express_words_are_back, review 108): the broker's ACL that
drops the express's sync words (express.py rule 8), the broker restarted with it, and two TCP
proxies in front of the broker that know each connection by the client id of its CONNECT:
``Gate`` (refuse some ids, hold what the broker sends one) and ``Cutter`` (cut some ids).
"""

from __future__ import annotations

import abc
import contextlib
import socket
import threading
from pathlib import Path
from typing import Any

from bridge.app import App
from bridge.emulators.pty import EmulatedPort
from bridge.interfaces.mqtt.express import express_client_id
from bridge.settings.mqtt import MqttSettings
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig
from tests.support.waiting import wait_until

OPEN = "topic readwrite rotor/#\ntopic readwrite homeassistant/#\n"
WORDS = "rotor/bridge/fence/express"  # the express's sync topic (express.py rule 8)


def acl_conf(tmp_path: Path, acl: str) -> str:
    """A broker conf (for a ``broker_conf`` fixture) reading its ACL from ``words.acl``."""
    (tmp_path / "words.acl").write_text(acl)
    return f"allow_anonymous true\nacl_file {tmp_path / 'words.acl'}\nuser root"


def express_holding(app: App) -> None:
    """The express up and holding the tower's port."""
    wait_until(app.express.up.is_set, 10, "the express up")
    wait_until(lambda: "tower" in app.express.held, 10, "the express holds the port")


def gated_start(rig: Rig, gate: Gate, **tower: Any) -> tuple[EmulatedPort[Any], MqttSettings, App]:
    """The bridge with its express started behind ``gate`` (what the broker sends the express
    the one ``gate`` may hold), its tower (``rig.add("tower", **tower)``) ready and the express
    holding its port."""
    rig.express = True
    emu = rig.add("tower", **tower)
    settings = rig.settings.mqtt
    gate.held_id = express_client_id(settings)
    app = rig.start()
    rig.ready("tower")
    express_holding(app)
    return emu, settings, app


def words_dropped(app: App, broker: Mosquitto, tmp_path: Path) -> None:
    """The broker restarted with the express's words denied; back when the express is
    subscribed again (its first word, dropped, is in the broker's log)."""
    (tmp_path / "words.acl").write_text(f"{OPEN}topic deny {WORDS}\n")
    start = broker.log.stat().st_size
    broker.restart()
    denied = f"Denied PUBLISH from {app.express.client_id}"  # its first word: it is subscribed
    wait_until(
        lambda: denied in broker.log.read_bytes()[start:].decode(errors="replace"),
        15,
        "the express back and subscribed, its word dropped",
    )


def client_id_of(packet: bytes) -> str | None:
    """The client id of an MQTT CONNECT (3.1.1 or 5) read whole, else None."""
    try:
        if packet[0] != 0x10:
            return None
        i = 1
        while packet[i] & 0x80:  # the remaining length
            i += 1
        i += 1
        i += 2 + int.from_bytes(packet[i : i + 2], "big")  # the protocol's name
        level, i = packet[i], i + 4  # level, flags, keep-alive
        if level == 5:  # its properties
            length, shift = 0, 0
            while True:
                byte, i = packet[i], i + 1
                length, shift = length | (byte & 0x7F) << shift, shift + 7
                if not byte & 0x80:
                    break
            i += length
        n = int.from_bytes(packet[i : i + 2], "big")
        return packet[i + 2 : i + 2 + n].decode()
    except (IndexError, UnicodeDecodeError):
        return None


class _Listening(abc.ABC):
    """A TCP listener on a port of its own, each connection accepted handed to ``_join`` on a
    thread of its own; the subclass's own state is set before this starts."""

    def __init__(self, backend: int) -> None:
        self._backend = backend
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port = self._listener.getsockname()[1]
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                client, _addr = self._listener.accept()
            except OSError:
                return
            threading.Thread(target=self._join, args=(client,), daemon=True).start()

    @abc.abstractmethod
    def _join(self, client: socket.socket) -> None:
        """One connection accepted: the subclass joins it to the broker, or closes it."""


class Gate(_Listening):
    """A TCP proxy in front of the broker that knows each connection by its client id: those
    in ``refused`` are closed at once (the broker away, for them alone), and while ``holding``
    what the broker sends the connection of ``held_id`` waits here, in order."""

    def __init__(self, backend: int) -> None:
        self.held_id = ""
        self.refused: set[str] = set()
        self._cond = threading.Condition()
        self._holding = False
        self._socks: list[socket.socket] = []
        super().__init__(backend)

    def hold(self, on: bool) -> None:
        with self._cond:
            self._holding = on
            self._cond.notify_all()

    def _join(self, client: socket.socket) -> None:
        try:
            connect = client.recv(65536)
            who = client_id_of(connect)
            if who is None or who in self.refused:
                client.close()
                return
            server = socket.create_connection(("127.0.0.1", self._backend))
            server.sendall(connect)
        except OSError:
            client.close()
            return
        self._socks += [client, server]
        threading.Thread(target=self._pipe, args=(client, server, False), daemon=True).start()
        self._pipe(server, client, who == self.held_id)

    def _pipe(self, a: socket.socket, b: socket.socket, held: bool) -> None:
        with contextlib.suppress(OSError):
            while data := a.recv(65536):
                with self._cond:
                    self._cond.wait_for(lambda: not (held and self._holding))
                b.sendall(data)
        with contextlib.suppress(OSError):
            b.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self.hold(False)
        self._listener.close()
        for s in self._socks:
            s.close()


class Cutter(_Listening):
    """A TCP proxy in front of the broker that knows each connection by its client id and can
    cut those named (and keep them out from then on)."""

    def __init__(self, backend: int) -> None:
        self._refused: set[str] = set()
        self._lock = threading.Lock()
        self._socks: dict[str, list[socket.socket]] = {}
        super().__init__(backend)

    def cut(self, ids: set[str]) -> None:
        with self._lock:
            self._refused |= ids
            socks = [s for who in ids for s in self._socks.pop(who, [])]
        for s in socks:
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)
            s.close()

    def _join(self, client: socket.socket) -> None:
        try:
            connect = client.recv(65536)
            who = client_id_of(connect) or ""
            with self._lock:
                if who in self._refused:
                    client.close()
                    return
            server = socket.create_connection(("127.0.0.1", self._backend))
            server.sendall(connect)
        except OSError:
            client.close()
            return
        with self._lock:
            self._socks.setdefault(who, []).extend([client, server])
        threading.Thread(target=self._pipe, args=(client, server), daemon=True).start()
        self._pipe(server, client)

    @staticmethod
    def _pipe(a: socket.socket, b: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while data := a.recv(65536):
                b.sendall(data)
        with contextlib.suppress(OSError):
            b.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self._listener.close()
        with self._lock:
            socks = [s for group in self._socks.values() for s in group]
        for s in socks:
            s.close()
