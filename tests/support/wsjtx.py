"""WSJT-X's UDP messages encoded as WSJT-X writes them, for the tests: written from the fact
sheet (bridge/interfaces/wsjtx/messages.py's header, itself from WSJT-X's NetworkMessage.hpp), never
from the bridge's decoder, and judged by WSJT-X's own reference server (``udp_daemon``, Debian's
``wsjtx`` package) in tests/wsjtx/test_udp_daemon.py."""

from __future__ import annotations

import socket
import struct
from dataclasses import dataclass

MAGIC = 0xADBCCBDA
SCHEMA = 3  # QDataStream Qt 5.4: what WSJT-X 2.x sends once a server answered with 3 (else 2)
HEARTBEAT, STATUS, QSO_LOGGED = 0, 1, 5
NOT_APPLICABLE = 0xFFFFFFFF  # a quint32 field that does not apply (frequency tolerance, T/R)


def u8(value: int) -> bytes:
    return struct.pack(">B", value)


def u32(value: int) -> bytes:
    return struct.pack(">I", value)


def i64(value: int) -> bytes:
    return struct.pack(">q", value)


def u64(value: int) -> bytes:
    return struct.pack(">Q", value)


def flag(value: bool) -> bytes:
    return b"\x01" if value else b"\x00"


def utf8(text: str | None) -> bytes:
    """A QByteArray: a quint32 length and the bytes; None is the null string (0xFFFFFFFF)."""
    if text is None:
        return u32(0xFFFFFFFF)
    data = text.encode("utf-8")
    return u32(len(data)) + data


def header(kind: int, instance: str = "WSJT-X", schema: int = SCHEMA) -> bytes:
    return u32(MAGIC) + u32(schema) + u32(kind) + utf8(instance)


def heartbeat(instance: str = "WSJT-X", version: str = "2.6.1", revision: str = "") -> bytes:
    return header(HEARTBEAT, instance) + u32(SCHEMA) + utf8(version) + utf8(revision)


@dataclass(frozen=True)
class StatusFields:
    """A Status message's fields in the order they are sent (the fact sheet)."""

    dx_call: str = ""
    dx_grid: str = ""
    transmitting: bool = False
    instance: str = "WSJT-X"
    dial_hz: int = 14_074_000
    mode: str = "FT8"
    report: str = "-10"
    tx_mode: str = "FT8"
    tx_enabled: bool = False
    decoding: bool = False
    rx_df: int = 1500
    tx_df: int = 1200
    de_call: str = "DL1XYZ"
    de_grid: str = "JO62"
    tx_watchdog: bool = False
    sub_mode: str = ""
    fast_mode: bool = False
    special_mode: int = 0
    tolerance_hz: int = NOT_APPLICABLE
    tr_period_s: int = 15
    configuration: str = "Default"
    tx_message: str = ""


def status(f: StatusFields, *, schema: int = SCHEMA) -> bytes:
    """A Status message (type 1), every field WSJT-X 2.6 sends."""
    return b"".join(
        (
            header(STATUS, f.instance, schema),
            u64(f.dial_hz),
            utf8(f.mode),
            utf8(f.dx_call),
            utf8(f.report),
            utf8(f.tx_mode),
            flag(f.tx_enabled),
            flag(f.transmitting),
            flag(f.decoding),
            u32(f.rx_df),
            u32(f.tx_df),
            utf8(f.de_call),
            utf8(f.de_grid),
            utf8(f.dx_grid),
            flag(f.tx_watchdog),
            utf8(f.sub_mode),
            flag(f.fast_mode),
            u8(f.special_mode),
            u32(f.tolerance_hz),
            u32(f.tr_period_s),
            utf8(f.configuration),
            utf8(f.tx_message),
        )
    )


def date_time(julian_day: int, ms_of_day: int) -> bytes:
    """A QDateTime (Qt 5.4 stream): QDate as a qint64 Julian day, QTime as quint32 ms since
    midnight, timespec quint8 1 (UTC)."""
    return i64(julian_day) + u32(ms_of_day) + u8(1)


def qso_logged(dx_call: str, dx_grid: str, instance: str = "WSJT-X") -> bytes:
    """A QSO Logged message (type 5): the message WSJT-X's reference server prints the DX call
    and grid of (its Status handler prints only the frequency and the mode)."""
    when = date_time(2_461_000, 12 * 3_600_000)
    return b"".join(
        (
            header(QSO_LOGGED, instance),
            when,
            utf8(dx_call),
            utf8(dx_grid),
            u64(14_074_000),
            utf8("FT8"),
            utf8("-10"),
            utf8("-12"),
            utf8("100"),
            utf8(""),
            utf8(""),
            when,
            utf8(""),
            utf8("DL1XYZ"),
            utf8("JO62"),
            utf8(""),
            utf8(""),
            utf8(""),
        )
    )


def send(datagram: bytes, address: tuple[str, int]) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.sendto(datagram, address)
