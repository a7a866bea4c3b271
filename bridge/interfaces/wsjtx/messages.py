"""WSJT-X's (and JTDX's) UDP messages, decoded. Pure: bytes in, a typed message or Malformed
out; no socket, no clock.

The fact sheet, written from WSJT-X's ``Network/NetworkMessage.hpp`` (the protocol's own
description, read for facts; none of its code is used):

- One message per UDP datagram, big-endian, written with Qt's QDataStream (schema 2: Qt 5.2,
  schema 3: Qt 5.4; both encode every field below the same way).
- Header: ``quint32`` magic 0xADBCCBDA; ``quint32`` schema number; ``quint32`` message type;
  ``utf8`` Id (the instance's unique key, e.g. ``WSJT-X`` or ``WSJT-X - IC-7300``). The schema
  is negotiated (MessageClient.cpp): WSJT-X 2.x starts with 2 and moves up to 3 only once a
  server's reply names 3. The bridge never replies, so WSJT-X sends it 2, or 3 when another
  program in the same multicast group (GridTracker, JTAlert) has answered; 1 is broken Qt 5.0
  and never sent. WSJT-X also never sends a message identical to the one before it.
- QDataStream encodings: ``quint32`` 4 bytes, ``quint64`` 8 bytes, ``quint8`` 1 byte, ``bool``
  one byte (0 false, anything else true). ``utf8`` is a QByteArray: a ``quint32`` length, then
  that many bytes of UTF-8, no terminator; length 0xFFFFFFFF is a null string (read here as
  empty), 0 an empty one.
- Type 0, Heartbeat (out/in, every 15 s, NetworkMessage::pulse): Id, maximum schema
  ``quint32``, version ``utf8``, revision ``utf8`` (the last three may be missing from old
  clients).
- Type 1, Status (out: sent at start-up and whenever its state changes: the DX call or grid,
  Tx enabled, switching between transmit and receive, the start and end of decoding...), in
  this order: Id ``utf8``, Dial frequency (Hz) ``quint64``, Mode ``utf8``, DX call ``utf8``,
  Report ``utf8``, Tx Mode ``utf8``, Tx Enabled ``bool``, Transmitting ``bool``, Decoding
  ``bool``, Rx DF ``quint32``, Tx DF ``quint32``, DE call ``utf8``, DE grid ``utf8``, DX grid
  ``utf8``, Tx Watchdog ``bool``, Sub-mode ``utf8``, Fast mode ``bool``, Special operation
  mode ``quint8``, Frequency tolerance ``quint32``, T/R period ``quint32``, Configuration name
  ``utf8``, Tx message ``utf8``.
- Other types (2 Decode, 3 Clear, 5 QSO Logged, 6 Close, ...) are not needed to follow a QSO
  partner and are ignored. The protocol's own rules: unknown message types are ignored
  silently, and fields added later come after the known ones, so extra bytes after them are
  ignored too.

Rules:
1. ``decode`` takes any bytes: a datagram that is not wholly a message this module knows
   (wrong magic, an unknown schema, a length past the end, a string that is not UTF-8, more
   than MAX_DATAGRAM bytes) raises Malformed with the reason; nothing else ever comes out.
2. A Status must carry every field up to the DX grid (what following needs); fields after it
   (added over the years) may be missing, and bytes after the last known one are ignored
   (the protocol's rule for fields added later).
3. A message type other than Heartbeat and Status decodes as ``Other`` (ignored, not junk).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

MAGIC = 0xADBCCBDA
SCHEMAS = (2, 3)  # Qt 5.2 and Qt 5.4 QDataStream; both encode these fields alike
HEARTBEAT = 0
STATUS = 1
NULL_LENGTH = 0xFFFFFFFF  # a null QByteArray
MAX_DATAGRAM = 16384  # a Status is a few hundred bytes; a 64 KB datagram is junk
MAX_STRING = 1024  # no field of a Status is longer (a Tx message is 37 characters)


class Malformed(ValueError):
    """Not a message this module knows; the message says why (for a rate-limited log)."""


@dataclass(frozen=True)
class Heartbeat:
    instance: str  # the Id
    max_schema: int | None = None
    version: str = ""
    revision: str = ""


@dataclass(frozen=True)
class Status:
    instance: str  # the Id
    dial_hz: int
    mode: str
    dx_call: str
    report: str
    tx_mode: str
    tx_enabled: bool
    transmitting: bool
    decoding: bool
    rx_df: int
    tx_df: int
    de_call: str
    de_grid: str
    dx_grid: str


@dataclass(frozen=True)
class Other:
    """A message type nobody here needs (rule 3)."""

    instance: str
    kind: int


Message = Heartbeat | Status | Other


class _Reader:
    """QDataStream's reading of the fields above; every short read is Malformed."""

    def __init__(self, data: bytes) -> None:
        self.data, self.at = data, 0

    @property
    def left(self) -> int:
        return len(self.data) - self.at

    def _take(self, n: int, what: str) -> bytes:
        if self.left < n:
            raise Malformed(f"{what}: {n} bytes needed, {self.left} left")
        chunk = self.data[self.at : self.at + n]
        self.at += n
        return chunk

    def u32(self, what: str) -> int:
        value: int = struct.unpack(">I", self._take(4, what))[0]
        return value

    def u64(self, what: str) -> int:
        value: int = struct.unpack(">Q", self._take(8, what))[0]
        return value

    def flag(self, what: str) -> bool:
        return self._take(1, what) != b"\0"

    def utf8(self, what: str) -> str:
        length = self.u32(what)
        if length == NULL_LENGTH:
            return ""
        if length > MAX_STRING:
            raise Malformed(f"{what}: length {length} past any field's")
        try:
            return self._take(length, what).decode("utf-8")
        except UnicodeDecodeError:
            raise Malformed(f"{what}: not UTF-8") from None


def status_instance(datagram: bytes) -> str | None:
    """The Id of a datagram whose header says it is a Status, read from its header alone
    (server.py rule 5: whose room it may take before it is decoded); None for anything else,
    a malformed header included."""
    if len(datagram) > MAX_DATAGRAM:
        return None
    r = _Reader(datagram)
    try:
        if r.u32("magic") != MAGIC or r.u32("schema") not in SCHEMAS or r.u32("type") != STATUS:
            return None
        return r.utf8("id")
    except Malformed:
        return None


def decode(datagram: bytes) -> Message:
    """One datagram as a message, or Malformed (rule 1)."""
    if len(datagram) > MAX_DATAGRAM:
        raise Malformed(f"{len(datagram)} bytes: no WSJT-X message is that long")
    r = _Reader(datagram)
    magic = r.u32("magic")
    if magic != MAGIC:
        raise Malformed(f"magic {magic:#010x}, not {MAGIC:#010x}")
    schema = r.u32("schema")
    if schema not in SCHEMAS:
        raise Malformed(f"schema {schema} unknown (known: 2, 3)")
    kind = r.u32("type")
    instance = r.utf8("id")
    if kind == HEARTBEAT:
        if r.left == 0:
            return Heartbeat(instance)
        return Heartbeat(instance, r.u32("maximum schema"), r.utf8("version"), r.utf8("revision"))
    if kind != STATUS:
        return Other(instance, kind)  # rule 3
    return Status(  # rule 2: the fields in the order they come (the keywords run in order)
        instance=instance,
        dial_hz=r.u64("dial frequency"),
        mode=r.utf8("mode"),
        dx_call=r.utf8("DX call"),
        report=r.utf8("report"),
        tx_mode=r.utf8("Tx mode"),
        tx_enabled=r.flag("Tx enabled"),
        transmitting=r.flag("transmitting"),
        decoding=r.flag("decoding"),
        rx_df=r.u32("Rx DF"),
        tx_df=r.u32("Tx DF"),
        de_call=r.utf8("DE call"),
        de_grid=r.utf8("DE grid"),
        dx_grid=r.utf8("DX grid"),
    )
