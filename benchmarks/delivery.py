"""When the broker handed a message on: a raw MQTT 3.1.1 subscriber whose every PUBLISH carries
the kernel's receive stamp, on the benchmarks' clock (time.monotonic).

Why: a stop's time from its publish to the controller includes the broker's own wait before it
passes the STOP on (mosquitto is one thread: under a backlog it is still passing on the messages
published before the STOP). Only the broker's delivery tells that wait apart from the bridge's.
This subscriber, connected and subscribed before the bridge, is served first (rule 2), so the
moment it is handed a message is the earliest any subscriber was: what a stop's time counts as
the broker's is never more than the bridge waited for it.

Rules:
1. No client library: CONNECT (3.1.1, clean session, keep-alive 0: nothing to ping), one
   SUBSCRIBE at QoS 0 to the exact filters given, then PUBLISH packets read one at a time on a
   thread of its own. A QoS 0 delivery is one packet with nothing to acknowledge.
2. Served first: mosquitto passes a message to the subscribers of one filter in the order they
   subscribed to it, writing each one's copy as it goes, and it visits a topic's exact filter
   before a wildcard one. So the probe subscribes to the same exact topics as the bridge's
   connections (``rotor/m0/stop``, not ``rotor/+/stop``), before the bridge starts, and never
   reconnects (a new subscription would come last): once its connection ends (``error``) it
   sees nothing more, and every later message is a miss its user counts.
3. The stamp: SO_TIMESTAMPNS (35 on Linux) puts the kernel's receive time of the data read
   (CLOCK_REALTIME, ns) in each ``recvmsg``'s ancillary data. On loopback that is taken in the
   broker's own send, the moment it handed the copy over. The probe reads each MQTT packet's
   exact length, so the stamp kept for a packet is that of the read that took its last byte
   (a TCP read is stamped with the last segment it took from): a reader late by any amount
   still stamps each packet at its arrival, never at a later one's. TCP_QUICKACK after each
   read: the broker's next copy to us never waits for a delayed ACK (Nagle's algorithm).
4. The clock: a stamp becomes time.monotonic's by the offset ``time.time() - time.monotonic()``,
   taken at the start and again after every packet, each time as the narrowest of three
   bracketed readings. The two clocks run at one rate (NTP's slewing adjusts both), so the
   offset changes only when the wall clock is stepped; ``offset_moved_s`` says the largest
   change seen (0 on a quiet host). A stamp converted with the offset read just after it is
   off by at most half its bracket (``offset_error_s``, the widest: microseconds), plus a step
   of the wall clock between the segment's arrival and our read (which ``offset_moved_s``
   would show).
5. ``delivered(topic, payload)``: the first delivery of that exact message, waited for up to a
   timeout (the kernel stamped it on arrival; only our thread may be late to read it).
6. Stamps live before the probe is handed out: Linux turns receive stamps on for the whole
   system in a work item of its own after the first socket asks (``net_enable_timestamp``,
   deferred), and until it has run, packets arrive unstamped: a message then was never
   recorded, a miss (seen in a test on a loaded host). So the probe also subscribes to a topic
   of its own and publishes to it until a copy comes back stamped, or says it cannot.
"""

from __future__ import annotations

import socket
import struct
import threading
import time

from tests.support.mqtt import variable_length

SO_TIMESTAMPNS = 35  # = SCM_TIMESTAMPNS, Linux (asm-generic/socket.h); Python names neither
_TIMESPEC = struct.Struct("@qq")  # the old struct timespec: 64-bit seconds and nanoseconds
_CMSG_SPACE = socket.CMSG_SPACE(_TIMESPEC.size)


class ProbeError(RuntimeError):
    pass


def _text(s: str) -> bytes:
    data = s.encode()
    return struct.pack("!H", len(data)) + data


def connect_packet(client_id: str) -> bytes:
    body = _text("MQTT") + bytes([4, 0x02]) + struct.pack("!H", 0) + _text(client_id)
    return b"\x10" + variable_length(len(body)) + body


def subscribe_packet(packet_id: int, filters: list[str]) -> bytes:
    body = struct.pack("!H", packet_id) + b"".join(_text(f) + b"\x00" for f in filters)
    return b"\x82" + variable_length(len(body)) + body


def publish_packet(topic: str, payload: bytes) -> bytes:
    """A QoS 0 PUBLISH (rule 6's own copy)."""
    body = _text(topic) + payload
    return b"\x30" + variable_length(len(body)) + body


def clock_offset_ns() -> tuple[int, int]:
    """time.time_ns() - time.monotonic_ns() as the narrowest of three bracketed readings, and
    that bracket's width (the offset is within half of it)."""
    best: tuple[int, int] | None = None
    for _ in range(3):
        m0 = time.monotonic_ns()
        real = time.time_ns()
        m1 = time.monotonic_ns()
        if best is None or m1 - m0 < best[1]:
            best = (real - (m0 + m1) // 2, m1 - m0)
    assert best is not None
    return best


class DeliveryProbe:
    """Connected and subscribed when built (rule 2: before the bridge); ``close`` ends it."""

    def __init__(
        self, port: int, filters: list[str], client_id: str = "", timeout_s: float = 10.0
    ) -> None:
        self.filters = list(filters)
        self.error: str | None = None  # why the connection ended (rule 2)
        self.offset_moved_s = 0.0  # rule 4
        self.offset_error_s = 0.0
        self._stamps: dict[tuple[str, bytes], float] = {}
        self._cond = threading.Condition()
        self._closing = False
        self._sock = socket.create_connection(("127.0.0.1", port), timeout=timeout_s)
        try:
            self._sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
            self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self._sock.sendall(connect_packet(client_id or f"stop-delivery-{id(self)}"))
            kind, body, _ = self._packet()
            if kind != 0x20 or body[1:2] != b"\x00":
                raise ProbeError(f"the broker refused the probe: {kind:#x} {body.hex()}")
            own = f"rotor-bridge-benchmark/{client_id or id(self)}/stamped"  # rule 6
            self._sock.sendall(subscribe_packet(1, [*self.filters, own]))
            kind, body, _ = self._packet()
            if kind != 0x90 or body[:2] != b"\x00\x01" or any(c & 0x80 for c in body[2:]):
                raise ProbeError(f"the broker refused the probe's subscription: {body.hex()}")
            self._stamps_live(own, timeout_s)
        except BaseException:
            self._sock.close()
            raise
        self._sock.settimeout(None)
        self._offset_ns, width = clock_offset_ns()
        self.offset_error_s = width / 2e9
        self._thread = threading.Thread(target=self._read, name="delivery-probe", daemon=True)
        self._thread.start()

    def _stamps_live(self, own: str, timeout_s: float) -> None:
        """Rule 6: a copy of our own message comes back stamped, or ProbeError."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            self._sock.sendall(publish_packet(own, b"?"))
            while True:
                kind, _body, stamp = self._packet()
                if kind >> 4 == 3:
                    break
            if stamp is not None:
                return
            time.sleep(0.01)  # (the kernel's work item is no event to wait on)
        raise ProbeError("the kernel does not stamp the probe's reads (SO_TIMESTAMPNS)")

    # -- reading (its own thread, once connected) -------------------------------------------
    def _exact(self, n: int) -> tuple[bytes, int | None]:
        """``n`` bytes, and the kernel's stamp of the read that took the last of them."""
        buf = bytearray()
        stamp: int | None = None
        while len(buf) < n:
            data, ancillary, _flags, _addr = self._sock.recvmsg(n - len(buf), _CMSG_SPACE)
            if not data:
                raise ProbeError("the broker closed the probe's connection")
            for level, kind, cdata in ancillary:
                if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS:
                    sec, nsec = _TIMESPEC.unpack(cdata[: _TIMESPEC.size])
                    stamp = sec * 1_000_000_000 + nsec
            buf += data
            # rule 3: the broker's next copy is not held for our ACK
            self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_QUICKACK, 1)
        return bytes(buf), stamp

    def _packet(self) -> tuple[int, bytes, int | None]:
        """One MQTT packet: its type (high nibble, flags kept), body and the last read's stamp."""
        head, stamp = self._exact(1)
        n, shift = 0, 0
        while True:
            byte, stamp = self._exact(1)
            n |= (byte[0] & 0x7F) << shift
            shift += 7
            if not byte[0] & 0x80:
                break
        if not n:
            return head[0], b"", stamp
        body, last = self._exact(n)
        return head[0], body, last if last is not None else stamp

    def _read(self) -> None:
        try:
            while True:
                kind, body, stamp = self._packet()
                if kind >> 4 != 3:  # only PUBLISH is expected (rule 1)
                    continue
                offset, width = clock_offset_ns()
                (size,) = struct.unpack_from("!H", body)
                topic = body[2 : 2 + size].decode()
                start = 2 + size + (2 if kind & 0x06 else 0)  # a packet id above QoS 0
                key = (topic, body[start:])
                with self._cond:
                    self.offset_moved_s = max(
                        self.offset_moved_s, abs(offset - self._offset_ns) / 1e9
                    )
                    self.offset_error_s = max(self.offset_error_s, width / 2e9)
                    self._offset_ns = offset
                    if stamp is not None and key not in self._stamps:
                        self._stamps[key] = (stamp - offset) / 1e9
                    self._cond.notify_all()
        except (OSError, ProbeError, struct.error, UnicodeDecodeError) as exc:
            with self._cond:
                if not self._closing:
                    self.error = str(exc) or type(exc).__name__
                self._cond.notify_all()

    # -- the benchmark's side ---------------------------------------------------------------
    def delivered(self, topic: str, payload: bytes, timeout_s: float = 2.0) -> float | None:
        """When the broker handed this message to the probe (time.monotonic), or None if it
        has not been read within ``timeout_s`` (rule 5)."""
        deadline = time.monotonic() + timeout_s
        key = (topic, payload)
        with self._cond:
            while key not in self._stamps and self.error is None:
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                self._cond.wait(left)
            return self._stamps.get(key)

    def close(self) -> None:
        with self._cond:
            self._closing = True
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self._sock.close()
        self._thread.join(5.0)
