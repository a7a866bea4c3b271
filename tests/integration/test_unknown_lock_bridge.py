"""The bridge's own moves at a start whose state file does not say the lock (runtime/kept.py
rule 10, session/parts.py rule 7), with real parts: the bridge (App) on an emulated Rotor-EZ
(pty), mosquitto down when it starts, so the first look cannot say the lock yet. Auto-park,
and the park of a storm the state file kept, wait until it has: a rotor locked for tower work
(the ON only the broker still held) must not turn by itself meanwhile."""

from __future__ import annotations

import time

import pytest

from bridge.runtime.state_store import StateStore
from tests.support.rig import Rig
from tests.support.waiting import wait_until

QUICK = {"brake_delay_s": 0.5, "settle_s": 0.3}
PARKING = {"park_az_deg": 0, "park_after_idle_s": 5, **QUICK}  # (the shortest spell allowed)
STORM = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180, **QUICK}
EMU = {"start_az_deg": 90, "brake_delay_s": 0.5, "jitter_deg": 0}
QUIET_S = 8.0  # a quiet period, not a deadline: longer than the quiet spell (5 s)


def _answering_unknown(rig: Rig) -> None:
    """The bridge started with the broker down: its controller answers, the lock not known."""
    app = rig.start()
    rotator = app._by_id["tower"]
    wait_until(lambda: rotator.status.available, 15, "the controller answers")
    assert rotator.status.lock_unknown


def _unturned(rig: Rig) -> bool:
    emu = rig.lines["tower"].emu
    moved = [f for f in emu.log() if f.data.startswith((b"AP", b"AM"))]
    return not moved and not emu.state().is_moving and abs(emu.state().az_deg - 90) < 1


def _stays_unturned(rig: Rig) -> None:
    """Through QUIET_S (a quiet period: waiting.py rule 2), the rotor never turned."""
    end = time.monotonic() + QUIET_S
    while time.monotonic() < end:
        assert _unturned(rig), rig.lines["tower"].emu.state()
        time.sleep(0.1)  # a poll, not a deadline


@pytest.mark.parametrize("said_off", [False, True], ids=["file says nothing", "file says OFF"])
def test_auto_park_waits_for_the_broker_to_say_the_lock(rig: Rig, said_off: bool) -> None:
    """A file that says OFF waits as one that says nothing (attack 15: its OFF cannot tell the
    broker's ON older or newer; it used to wait for no broker)."""
    rig.add("tower", emu=EMU, **PARKING)
    if said_off:
        assert StateStore(rig.settings.state_file).set_locked("tower", False)
    rig.broker.stop()
    _answering_unknown(rig)
    _stays_unturned(rig)
    rig.broker.start()  # (it holds no lock ON: the park goes)
    rig.arrived("tower", 0, timeout_s=30)


def test_a_kept_storms_park_waits_for_the_broker_to_say_the_lock(rig: Rig) -> None:
    rig.add("tower", emu=EMU, **STORM)
    assert StateStore(rig.settings.state_file).set_storm("tower", True)  # (no lock said)
    rig.broker.stop()
    _answering_unknown(rig)
    _stays_unturned(rig)
    rig.broker.start()
    rig.arrived("tower", 180, timeout_s=30)
