"""An MQTT-aware TCP proxy between the bridge and a broker, for the tests that place a message at
an exact moment of a connection's life (attack 32): each connection known by the client id of
its CONNECT; one dropped (its connection lost, the others left alone), what one sends held (a
busy uplink) and let go, the broker's SUBACKs to each counted (the moment a subscription
stands), and every connection open turned into a dead path (``blackhole``: nothing passes
either way, no socket closed, as a NAT that lost its table or a link that went away without
a word; new connections pass).
"""

from __future__ import annotations

import contextlib
import socket
import threading

CONNECT, SUBACK = 1, 9  # MQTT packet types


def _packets(buf: bytearray) -> list[bytes]:
    """Whole MQTT packets taken off the front of ``buf``."""
    out = []
    while len(buf) >= 2:
        n, mult, i = 0, 1, 1
        while True:
            if i >= len(buf):
                return out
            b = buf[i]
            i += 1
            n += (b & 127) * mult
            mult *= 128
            if not b & 128:
                break
        if len(buf) < i + n:
            return out
        out.append(bytes(buf[: i + n]))
        del buf[: i + n]
    return out


def _client_id(connect: bytes) -> str:
    i = 1
    while connect[i] & 128:
        i += 1
    i += 1
    i += 2 + int.from_bytes(connect[i : i + 2], "big")  # protocol name
    level = connect[i]
    i += 1 + 1 + 2  # level, flags, keep-alive
    if level == 5:  # properties
        n, mult = 0, 1
        while True:
            b = connect[i]
            i += 1
            n += (b & 127) * mult
            mult *= 128
            if not b & 128:
                break
        i += n
    size = int.from_bytes(connect[i : i + 2], "big")
    return connect[i + 2 : i + 2 + size].decode()


class _Stream:
    def __init__(self, client: socket.socket, server: socket.socket) -> None:
        self.client, self.server = client, server
        self.client_id = ""
        self.held: bytearray | None = None  # what the client sent while held
        self.dead = False  # a dead path: nothing passes either way (``blackhole``)
        self.lock = threading.Lock()


class MqttProxy:
    """Between the bridge and the broker: each connection known by its client id; ``drop`` one,
    ``hold`` what one sends (its bytes kept, in order) until ``release``; ``subacks`` counts the
    SUBACKs the broker sent each client id. A test's own proxy changes or loses one kind of
    packet by overriding ``on_packet``."""

    def __init__(self, backend: int) -> None:
        self._backend = backend
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port = self._listener.getsockname()[1]
        self._streams: list[_Stream] = []
        self.subacks: dict[str, int] = {}
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                client, _addr = self._listener.accept()
            except OSError:
                return
            try:
                server = socket.create_connection(("127.0.0.1", self._backend))
            except OSError:
                client.close()
                continue
            stream = _Stream(client, server)
            self._streams.append(stream)
            threading.Thread(target=self._up, args=(stream,), daemon=True).start()
            threading.Thread(target=self._down, args=(stream,), daemon=True).start()

    def _up(self, s: _Stream) -> None:
        buf = bytearray()
        with contextlib.suppress(OSError):
            while data := s.client.recv(65536):
                if s.dead:
                    continue
                buf += data
                for packet in _packets(buf):
                    if s.dead:  # (made dead by ``on_packet``, say: the rest is lost too)
                        break
                    if packet[0] >> 4 == CONNECT:
                        s.client_id = _client_id(packet)
                    if (passed := self.on_packet(s, packet, up=True)) is None:
                        continue
                    packet = passed
                    with s.lock:
                        if s.held is not None:
                            s.held += packet
                            continue
                    s.server.sendall(packet)
        with contextlib.suppress(OSError):
            s.server.shutdown(socket.SHUT_WR)

    def _down(self, s: _Stream) -> None:
        buf = bytearray()
        with contextlib.suppress(OSError):
            while data := s.server.recv(65536):
                if s.dead:
                    continue
                buf += data
                for packet in _packets(buf):
                    if s.dead:
                        break
                    if (passed := self.on_packet(s, packet, up=False)) is None:
                        continue
                    packet = passed
                    s.client.sendall(packet)
                    if packet[0] >> 4 == SUBACK:
                        self.subacks[s.client_id] = self.subacks.get(s.client_id, 0) + 1
        with contextlib.suppress(OSError):
            s.client.shutdown(socket.SHUT_WR)

    def on_packet(self, s: _Stream, packet: bytes, *, up: bool) -> bytes | None:
        """Each whole MQTT packet as it passes, ``up`` (the client's, to the broker) or down (the
        broker's, to the client), on that stream's own thread: what is handed on in its place
        (the packet itself here; a changed one), or None for none (the packet lost). Up, it
        comes after its CONNECT named the stream (``s.client_id``) and before ``hold``; down,
        before ``subacks`` counts what was handed on."""
        return packet

    def _of(self, client_id: str) -> list[_Stream]:
        return [s for s in self._streams if s.client_id == client_id]

    def drop(self, client_id: str) -> None:
        for s in self._of(client_id):
            self._streams.remove(s)
            for sock in (s.client, s.server):
                with contextlib.suppress(OSError):
                    sock.shutdown(socket.SHUT_RDWR)
                sock.close()

    def hold(self, client_id: str) -> None:
        for s in self._of(client_id):
            with s.lock:
                s.held = bytearray()

    def release(self, client_id: str) -> None:
        for s in self._of(client_id):
            with s.lock:
                held, s.held = s.held, None
                if held:
                    with contextlib.suppress(OSError):
                        s.server.sendall(held)

    def blackhole(self, client_id: str | None = None) -> None:
        """Every connection open now (``client_id``'s only, if given) is a dead path: what
        either side sends is lost, and neither side is told (no FIN, no RST); connections
        made after it pass."""
        for s in list(self._streams) if client_id is None else self._of(client_id):
            s.dead = True

    def close(self) -> None:
        self._listener.close()
        for s in self._streams:
            for sock in (s.client, s.server):
                sock.close()
