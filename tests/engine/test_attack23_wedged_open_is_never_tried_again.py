"""Attack 23, on a real pty with real pyserial: an open() of the serial port that never comes
back (a wedged USB adapter's driver) is waited for for ever, so the adapter unplugged and
plugged back in (its stable by-id name now on a new device) never brings the rotator back.

runtime/worker.py rule 4 puts the open on a thread of its own so that a wedged adapter holds up
no other line; but the worker starts no other attempt while that one has not returned
(``wants``: "until" infinite while ``PendingOpen.result`` is None): no timeout, no abandon. A
user who pulls and replugs the stuck adapter sees the rotator offline, every target refused and
every STOP only owed, never written, until the bridge is restarted. Now an open that has not
returned after OPEN_BOUND_S is given up and the port tried again (worker.py rule 4), so the
replugged adapter opens on the next attempt.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
import serial

from bridge import emulators
from bridge.app import worker_config
from bridge.emulators.pty import EmulatedPort
from bridge.protocols.base import ModelSpec
from bridge.runtime.lines import Lines
from bridge.runtime.port import open_port
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.settings import RotatorSettings
from tests.support import wait_until
from tests.support.rig import FAST_BRIDGE, FAST_ROTOR
from tests.support.waiting import slow

BACK_WITHIN_S = 30.0  # a hung open given up and the port tried again: generous (3 back-offs)


@pytest.fixture
def emu(tmp_path: Path) -> Iterator[EmulatedPort]:
    port = emulators.start("rotorez", link=str(tmp_path / "tty"), **FAST_ROTOR)
    yield port
    port.close()


def test_a_replugged_adapter_comes_back_after_an_open_that_hung(emu: EmulatedPort) -> None:
    release, hung = threading.Event(), threading.Event()
    calls: list[str] = []

    def opener(path: str, spec: ModelSpec, baud: int) -> serial.Serial:
        calls.append(path)
        if len(calls) == 1:  # the wedged adapter: its open() never returns while the test runs
            hung.set()
            release.wait(slow(120))  # a guard, past the test's end (not a deadline it judges)
            raise serial.SerialException("the wedged open let go")
        return open_port(path, spec, baud)  # the adapter replugged: a new device, it opens

    assert emu.link is not None
    settings = RotatorSettings.model_validate(
        {"id": "tower", "model": "rotorez", "port": emu.link, **FAST_BRIDGE}
    )
    rot = Rotator(
        worker_config(settings),
        StateStore(None),
        lambda s: None,
        lambda e: None,
        port_opener=opener,
        lines=Lines(),
    )
    rot.start()
    try:
        wait_until(hung.is_set, 10, "the first open() hanging")
        emu.unplug()  # the user pulls the stuck adapter...
        emu.replug()  # ...and plugs it back in
        came_back = True
        try:
            wait_until(lambda: rot.status.available, BACK_WITHIN_S, "the rotator online")
        except AssertionError:
            came_back = False
        assert came_back, (
            f"the rotator stayed offline {slow(BACK_WITHIN_S):g} s after the adapter was "
            f"replugged; open() was tried {len(calls)} time(s), the first still hanging"
        )
    finally:
        release.set()
        rot.stop()
