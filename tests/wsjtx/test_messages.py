"""WSJT-X's messages decoded (bridge/interfaces/wsjtx/messages.py), from datagrams the tests'
encoder writes from the fact sheet (tests/support/wsjtx.py, judged by WSJT-X's own udp_daemon in
test_udp_daemon.py): whole, with every field, and as junk of every kind."""

from __future__ import annotations

from dataclasses import replace

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bridge.interfaces.wsjtx.messages import (
    MAX_DATAGRAM,
    Heartbeat,
    Malformed,
    Other,
    Status,
    decode,
    status_instance,
)
from tests.support import wsjtx as w

QSO = w.StatusFields(dx_call="JA1ABC", dx_grid="PM95", transmitting=True, tx_enabled=True)


def test_a_status_decodes_every_field_following_needs_in_order() -> None:
    got = decode(w.status(QSO))
    assert got == Status(
        instance="WSJT-X",
        dial_hz=14_074_000,
        mode="FT8",
        dx_call="JA1ABC",
        report="-10",
        tx_mode="FT8",
        tx_enabled=True,
        transmitting=True,
        decoding=False,
        rx_df=1500,
        tx_df=1200,
        de_call="DL1XYZ",
        de_grid="JO62",
        dx_grid="PM95",
    )


def test_schema_2_jtdx_utf8_and_null_strings_decode() -> None:
    jtdx = replace(QSO, instance="JTDX", dx_call="ÖH2ÄB", dx_grid="KP20", dial_hz=50_313_000)
    got = decode(w.status(jtdx, schema=2))
    assert isinstance(got, Status)
    assert (got.instance, got.dx_call, got.dx_grid, got.dial_hz) == (
        "JTDX",
        "ÖH2ÄB",
        "KP20",
        50_313_000,
    )
    # a null QByteArray (length 0xFFFFFFFF) is an empty string, not junk
    datagram = w.status(replace(QSO, dx_grid="PM95"))
    nulled = datagram.replace(w.utf8("PM95"), w.utf8(None))
    got = decode(nulled)
    assert isinstance(got, Status) and got.dx_grid == "" and got.dx_call == "JA1ABC"


def test_fields_added_later_and_fields_after_the_dx_grid_missing_are_both_fine() -> None:
    """The protocol's rule: new fields come at the end (ignored); older programs send fewer."""
    full = w.status(QSO)
    assert decode(full + b"\x00\x01new field") == decode(full)
    grid_end = full.index(w.utf8("PM95")) + len(w.utf8("PM95"))
    assert decode(full[:grid_end]) == decode(full)


def test_heartbeat_and_other_types() -> None:
    assert decode(w.heartbeat(version="2.6.1", revision="abc")) == Heartbeat(
        "WSJT-X", 3, "2.6.1", "abc"
    )
    assert decode(w.header(w.HEARTBEAT)) == Heartbeat("WSJT-X")  # an old client's
    assert decode(w.qso_logged("JA1ABC", "PM95")) == Other("WSJT-X", w.QSO_LOGGED)
    assert decode(w.header(99, "X") + b"anything") == Other("X", 99)


@pytest.mark.parametrize(
    ("datagram", "why"),
    [
        (b"", "magic"),
        (w.u32(0xDEADBEEF) + w.status(QSO)[4:], "magic 0xdeadbeef"),
        (w.status(QSO)[:4] + w.u32(1) + w.status(QSO)[8:], "schema 1"),
        (w.status(QSO)[:4] + w.u32(4) + w.status(QSO)[8:], "schema 4"),
        (w.status(QSO)[:12] + w.u32(60_000) + w.status(QSO)[16:], "id: length 60000"),
        (w.status(QSO)[:12] + w.u32(10_000) + w.status(QSO)[16:], "id: length 10000"),
        (w.status(QSO)[:14], "id"),
        (w.status(QSO)[:28], "dial frequency"),
        (w.header(w.STATUS) + w.u64(1) + w.u32(3) + b"FT", "mode: 3 bytes needed"),
        (w.header(w.STATUS) + w.u64(1) + w.u32(2) + b"\xff\xfe", "mode: not UTF-8"),
        (b"\xff" * 65_000, "65000 bytes"),
    ],
)
def test_junk_is_malformed_with_its_reason(datagram: bytes, why: str) -> None:
    with pytest.raises(Malformed, match=why):
        decode(datagram)


def test_a_status_cut_anywhere_before_its_dx_grid_ends_is_malformed() -> None:
    full = w.status(QSO)
    grid_end = full.index(w.utf8("PM95")) + len(w.utf8("PM95"))
    for cut in range(grid_end):
        with pytest.raises(Malformed):
            decode(full[:cut])


@given(st.binary(max_size=600))
def test_any_bytes_decode_or_are_malformed_never_anything_else(data: bytes) -> None:
    try:
        decode(data)
    except Malformed:
        pass


@given(st.binary(max_size=200), st.integers(min_value=0, max_value=120))
def test_a_valid_status_with_its_tail_replaced_by_junk_never_raises_otherwise(
    junk: bytes, keep: int
) -> None:
    try:
        decode(w.status(QSO)[:keep] + junk)
    except Malformed:
        pass


def test_the_size_limit_is_far_above_any_status() -> None:
    assert len(w.status(replace(QSO, tx_message="CQ DX JA1ABC PM95" * 2))) < MAX_DATAGRAM // 20


def test_a_status_header_names_its_instance_and_nothing_else_does() -> None:
    """server.py rule 5 reads whose status it is before decoding it: a status's Id, and None
    for a heartbeat, another message, junk or a header cut short."""
    status = w.status(replace(QSO, instance="WSJT-X - IC7300"))
    assert status_instance(status) == "WSJT-X - IC7300"
    assert status_instance(w.heartbeat("WSJT-X")) is None
    assert status_instance(w.qso_logged("JA1ABC", "PM95")) is None
    assert status_instance(b"\x00" * 40) is None
    assert status_instance(status[:14]) is None
    assert status_instance(status + b"x" * MAX_DATAGRAM) is None


@given(st.binary(max_size=200))
def test_any_bytes_name_an_instance_or_none_never_anything_else(data: bytes) -> None:
    assert status_instance(data) is None or isinstance(status_instance(data), str)
