"""An eleventh attack pass, on the front ends together: the DCU-1 port's ``AP1`` bearing sent
before an MQTT STOP, read after it. Real parts: mosquitto, the bridge (App) with its DCU-1
TCP port (``dcu1_port``), an emulated Rotor-EZ on a pty.

gs232/ package rule 10 promises that ``AM1;`` turns to the ``AP1`` bearing only "if no STOP
or lock ON (from any interface) came after it: a bearing given before a STOP is never turned
to after it". The session keeps the rotator's halt count when it *reads* ``AP1``
(commands.py ``Dcu1Session.answer``), not the count of the look that held its bytes
(tcplines.py rule 9): a client whose thread sleeps over its budget (rule 5) has its ``AP1``
read after a STOP that came after it, the count then already holds the STOP, and the ``AM1;``
the program sends after the STOP turns the rotor to the bearing given before it.

The budget is gated as in test_attack_fence_pause.py (no clock, no sleep).
"""

from __future__ import annotations

import json
import os
import select
import socket
import time
from pathlib import Path

import pytest

from bridge.interfaces import ptylines, tcplines
from bridge.interfaces.ptylines import PtyLineServer
from tests.integration.test_attack_fence_pause import mqtt_stop_carried, read_gate, shut_after_read
from tests.support import free_port
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until
from tests.test_ptylines import Client


def _read(sock: socket.socket, size: int) -> bytes:
    got = b""
    while len(got) < size:
        chunk = sock.recv(size - len(got))
        assert chunk, f"the DCU-1 port closed after {got!r}"
        got += chunk
    return got


def test_an_ap1_bearing_sent_before_an_mqtt_stop_is_not_turned_to_after_it(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A logger polls the DCU-1 port fast enough to be over its budget, stores 200 with AP1;
    Home Assistant's STOP comes; the logger then sends AM1;. The rotor turned to 200."""
    gate, spent = read_gate(monkeypatch, tcplines)
    port = free_port()
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0}, dcu1_port=port)
    app = rig.start()
    rig.ready("tower")
    (server,) = app.emulations
    with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as sock:
        spent.clear()
        sock.sendall(b"AI1;")
        assert _read(sock, 4) == b";010"
        shut_after_read(gate, spent)  # over its budget from its next read on (a fast poller's)
        sock.sendall(b"AI1;")
        assert _read(sock, 4) == b";010"  # read and answered: its thread now sleeps
        sock.sendall(b"AP1200;")  # sent now, before the STOP: in the kernel, unread
        mqtt_stop_carried(rig, emu, server)  # the STOP carried out
        t = time.monotonic()
        sock.sendall(b"AM1;")  # after the STOP
        gate.set()
        wait_until(
            lambda: emu.state().is_moving or refused(rig, t),
            slow(10),
            "the AM1; carried out or refused",
        )
    assert not emu.state().is_moving, "turned to the AP1 bearing given before the STOP"


def refused(rig: Rig, after: float) -> bool:
    """R/error said, since ``after``, that the AM1; came after a STOP."""
    m = rig.probe.last("rotor/error")
    return m is not None and m.t >= after and "AM1" in json.loads(m.payload).get("message", "")


def test_an_ap1_bearing_written_to_the_pty_before_an_mqtt_stop_is_not_turned_to_after_it(
    rig: Rig, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same on the DCU-1 pty (ptylines.py rule 10: the same session, its fence told the
    look that held the bytes): AP1200; written while the thread sleeps over its budget, an MQTT
    STOP, then AM1;. The rotor stays still."""
    gate, spent = read_gate(monkeypatch, ptylines)
    path = str(tmp_path / "rotor-dcu1")
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0}, dcu1_pty=path)
    app = rig.start()
    rig.ready("tower")
    (server,) = [e for e in app.emulations if isinstance(e, PtyLineServer) and e.path == path]
    client = Client(path)
    try:
        spent.clear()
        assert _answer(client, b"AI1;") == b";010"
        shut_after_read(gate, spent)  # over its budget from its next read on
        assert _answer(client, b"AI1;") == b";010"  # read and answered: its thread now sleeps
        os.write(client.fd, b"AP1200;")  # before the STOP: in the pty, unread
        wait_until(lambda: tcplines.unread(server._master) == 7, slow(5), "the AP1 in the pty")
        mqtt_stop_carried(rig, emu, server)  # the STOP carried out
        t = time.monotonic()
        os.write(client.fd, b"AM1;")  # after the STOP
        gate.set()
        wait_until(
            lambda: emu.state().is_moving or refused(rig, t),
            slow(10),
            "the AM1; carried out or refused",
        )
    finally:
        client.close()
    assert not emu.state().is_moving, "turned to the AP1 bearing given before the STOP"


def _answer(client: Client, command: bytes) -> bytes:
    """``command`` written to the pty and its four-byte answer read."""
    os.write(client.fd, command)
    got = b""
    while len(got) < 4:
        chunk = _read_some(client)
        assert chunk, f"the DCU-1 pty answered {got!r} only"
        got += chunk
    return got


def _read_some(client: Client) -> bytes:
    ready = select.select([client.fd], [], [], slow(5))[0]
    return os.read(client.fd, 4) if ready else b""
