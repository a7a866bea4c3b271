"""The worker's wiring (runtime/lines.py + worker.py), with real parts: a real pty driven by the
emulator, real pyserial.

What is proven here is what no virtual-time scenario can show: that the thread wakes at once for
a command (the mailbox pipe) and that nothing a listener does reaches the serial line.
"""

from __future__ import annotations

import random
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import serial

from bridge import emulators
from bridge.app import worker_config
from bridge.core.model import ErrorEvent, RotatorStatus, Stop, Target
from bridge.emulators.pty import EmulatedPort
from bridge.protocols.base import ModelSpec
from bridge.runtime.port import open_port
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.settings import RotatorSettings
from tests.support import wait_until
from tests.support.rig import FAST_BRIDGE, FAST_ROTOR
from tests.support.waiting import factor


@pytest.fixture
def emu(tmp_path: Path) -> Iterator[EmulatedPort]:
    port = emulators.start("rotorez", link=str(tmp_path / "tty"), **FAST_ROTOR)
    yield port
    port.close()


class Opens:
    """Counts how often the worker opens its port."""

    def __init__(self) -> None:
        self.count = 0

    def __call__(self, path: str, spec: ModelSpec, baud: int) -> serial.Serial:
        self.count += 1
        return open_port(path, spec, baud)


# Polls this far apart that only the mailbox's wake-up can bring a stop out within STOP_WAIT_S:
# a lost wake-up would leave it for the next poll, seconds later, and the wait would fail.
SLOW_POLLS = {
    "idle_poll_interval_s": 1.5,
    "moving_poll_interval_s": 1.5,
    "settle_s": 3.0,
    "stall_timeout_s": 60.0,
    "silence_timeout_s": 30.0,
}
STOP_WAIT_S = 0.5  # a guard well inside one poll interval, not a latency bound


def slowed_polls() -> tuple[dict[str, float], float]:
    """SLOW_POLLS and STOP_WAIT_S both made longer by the machine's factor (waiting.py rule 1),
    so that the wait stays a third of a poll interval on a busy machine: a stop that only the
    next poll brings out still misses it, and one the wake-up brings out is not timed out by
    the load (CI, under another process's flood: a wait of 0.5 s, unscaled, timed out)."""
    f = factor()
    polls = dict(SLOW_POLLS)
    for key in ("idle_poll_interval_s", "moving_poll_interval_s", "settle_s"):
        polls[key] *= f
    return polls, STOP_WAIT_S * f


FINAL_TRIALS = 5


def make_rotator(
    emu: EmulatedPort,
    on_status: Callable[[RotatorStatus], None],
    events: list,
    opens: Opens,
    polls: dict[str, float] | None = None,
) -> Rotator:
    assert emu.link is not None
    settings = RotatorSettings.model_validate(
        {"id": "t", "model": "rotorez", "port": emu.link, **FAST_BRIDGE, **(polls or {})}
    )
    cfg = worker_config(settings)
    return Rotator(cfg, StateStore(None), on_status, events.append, port_opener=opens)


def test_a_listener_that_raises_on_every_status_never_touches_the_serial_line(
    emu: EmulatedPort, caplog: pytest.LogCaptureFixture
) -> None:
    calls = []

    def broken_listener(status: RotatorStatus) -> None:
        calls.append(status)
        raise RuntimeError("display is broken")

    events: list[ErrorEvent] = []
    opens = Opens()
    rot = make_rotator(emu, broken_listener, events, opens)
    rot.start()
    try:
        wait_until(lambda: rot.status.state.value == "idle", 10, "idle")
        rot.submit(Target(100.0))
        emu.wait_for(lambda s: abs(s.az_deg - 100) <= 2 and not s.is_moving, timeout_s=15)
        wait_until(lambda: rot.status.state.value == "idle", 10, "idle after the move")
        assert rot.status.available
    finally:
        rot.stop()
    assert opens.count == 1  # the port was never closed and reopened
    assert not [e for e in events if e.kind in ("internal", "serial")]
    assert len(calls) > 5  # the listener kept being called
    logged = [r for r in caplog.records if "display is broken" in str(r.exc_info)]
    assert len(logged) == 1  # logged once per kind, not once per status


def test_a_stop_right_behind_a_target_reaches_the_controller_at_once(emu: EmulatedPort) -> None:
    """300 times a target and then a stop 0-3 ms later: every stop behind a target that went
    out is on the wire before the next poll could have carried it (the mailbox wake-up must
    never be lost, or a stop waits for a poll); a target the stop caught before it went out
    needs none (stops merge). Polls are SLOW_POLLS apart, so the proof is the order, not a
    measured latency."""
    events: list[ErrorEvent] = []
    polls, stop_wait_s = slowed_polls()
    rot = make_rotator(emu, lambda s: None, events, Opens(), polls)
    rot.start()
    rng = random.Random(13)
    stops = 0
    try:
        wait_until(lambda: rot.status.state.value == "idle", 20, "idle")
        for _ in range(300):
            seen = len(emu.frames())
            rot.submit(Target(float(rng.randint(0, 359))))
            _spin(rng.uniform(0, 0.003))
            t_put = time.monotonic()
            rot.submit(Stop())

            def settled(device, _now: float, seen: int = seen, t: float = t_put):  # noqa: ANN001
                new = device.log[seen:]
                went = any(f.data.startswith(b"AP1") for f in new)
                stops = [f for f in new if f.data == b";" and f.time_s >= t]
                if went:
                    return stops  # the target went out: its stop must follow
                return [None] if rot.status.target_az_deg is None else []  # caught in time

            frames = emu.wait_until(settled, bool, timeout_s=stop_wait_s)
            stops += frames[0] is not None
        # then FINAL_TRIALS more with the target surely out first: on a loaded machine every
        # stop above may have caught its target in the mailbox. A lost wake-up leaves a stop for
        # the next poll, anywhere in the SLOW_POLLS interval, so each trial catches it with a
        # chance of 2/3 and all of them miss it one time in 240 (the rotor comes to rest
        # before each: a target is not sent while it may still turn)
        for _ in range(FINAL_TRIALS):
            wait_until(lambda: rot.status.state.value == "idle", 20, "idle")
            seen = len(emu.frames())
            rot.submit(Target(180.0 if emu.state().az_deg < 90 else 0.0))
            emu.wait_until(
                lambda d, _now, seen=seen: any(f.data.startswith(b"AP1") for f in d.log[seen:]),
                bool,
            )
            t_put = time.monotonic()
            rot.submit(Stop())
            emu.wait_until(
                lambda d, _now, seen=seen, t=t_put: [
                    f for f in d.log[seen:] if f.data == b";" and f.time_s >= t
                ],
                bool,
                timeout_s=stop_wait_s,
            )
            stops += 1
    finally:
        rot.stop()
    assert stops >= FINAL_TRIALS
    assert not emu.state().is_moving


def _spin(duration_s: float) -> None:
    """Hold the thread for a few milliseconds (time.sleep's granularity is too coarse here)."""
    end = time.monotonic() + duration_s
    while time.monotonic() < end:
        threading.Event().wait(0)  # a yield, not a deadline
