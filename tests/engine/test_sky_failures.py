"""A sky that cannot be computed, and a part of the session that raises, never take the serial
link down (session.py rules 11 and 14, tracking.py rule 8; docs/architecture.md: a feature's
failure is contained, and a stop is never lost).

Found in review: a JSON TLE whose orbit has decayed, or a clock past the ephemeris's end
(DE421 ends in 2053), raised inside the rotator's step; the worker called it an unexpected
error and closed the port, and a STOP published 50 ms later was dropped on the closed port:
the rotor ran on to its old target. Here with real parts (a pty, the SPID emulator, the lines
thread, the sky worker's thread); the wall clock is the test's own.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import serial

from bridge import emulators
from bridge.app import worker_config
from bridge.core.model import ErrorEvent, ErrorKind, RotatorStatus, Source, Stop, Target, TrackBody
from bridge.emulators.pty import EmulatedPort
from bridge.protocols.base import ModelSpec
from bridge.runtime.port import open_port
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.session import autopark
from bridge.settings import RotatorSettings
from bridge.sky import Body, Sky
from tests.engine.virtual import VirtualRotator
from tests.support import wait_until
from tests.support.rig import FAST_SPID_BRIDGE
from tests.support.sky import synthetic_tle

BERLIN = (52.52, 13.29)
TLE_EPOCH = 1_735_689_600.0  # 2025-01-01 00:00 UTC
DAY_S = 86400.0
PAST_2053 = 2_700_000_000.0  # 2055-07-23: beyond DE421


@pytest.fixture
def md01(tmp_path: Path) -> Iterator[EmulatedPort]:
    port = emulators.start(
        "md01", link=str(tmp_path / "tty"), az_speed_deg_s=10.0, el_speed_deg_s=10.0
    )
    yield port
    port.close()


def make_rotator(
    emu: EmulatedPort, wall_at_start: float, events: list[ErrorEvent], opens: list[str]
) -> Rotator:
    assert emu.link is not None
    settings = RotatorSettings.model_validate(
        {
            "id": "t",
            "model": "md01",
            "port": emu.link,
            "az_speed_deg_s": 10.0,
            "el_speed_deg_s": 10.0,
            **FAST_SPID_BRIDGE,
        }
    )
    t0 = time.monotonic()

    def opener(path: str, spec: ModelSpec, baud: int) -> serial.Serial:
        opens.append(path)
        return open_port(path, spec, baud)

    def on_status(_status: RotatorStatus) -> None:
        pass

    return Rotator(
        worker_config(settings, Sky(*BERLIN)),
        StateStore(None),
        on_status,
        events.append,
        wall=lambda: wall_at_start + time.monotonic() - t0,
        port_opener=opener,
    )


def decayed() -> tuple[str, str, str]:
    """Fine at its epoch (Body accepts it); a drag term that brings it down within months."""
    line1, line2 = synthetic_tle(
        "LOW", TLE_EPOCH, inclination_deg=51.6, raan_deg=0.0, mean_anomaly_deg=0.0, bstar=0.05
    )
    return "LOW", line1, line2


@pytest.mark.parametrize(
    ("what", "wall", "track", "reason"),
    [
        ("a decayed TLE", TLE_EPOCH + 400 * DAY_S, decayed, "satellite orbit decayed"),
        ("past 2053", PAST_2053, lambda: None, "date beyond the ephemeris (2053)"),
    ],
)
def test_a_sky_that_cannot_be_computed_ends_tracking_and_a_stop_right_after_reaches_the_rotor(
    md01: EmulatedPort,
    what: str,
    wall: float,
    track: Callable[[], tuple[str, str, str] | None],
    reason: str,
) -> None:
    events: list[ErrorEvent] = []
    opens: list[str] = []
    rot = make_rotator(md01, wall, events, opens)
    rot.start()
    try:
        wait_until(lambda: rot.status.available and rot.status.state.value == "idle", 10, "idle")
        rot.submit(Target(300.0))  # 30 s away at 10 deg/s
        md01.wait_for(lambda s: s.is_moving, 5)
        tle = track()
        rot.submit(TrackBody(tle[0] if tle else "sun", tle, source=Source.MQTT), f"track {what}")
        # the failure is found (on the sky worker) and tracking ends with its reason: the
        # port stays open, so the STOP that follows reaches the rotor
        wait_until(lambda: rot.status.tracking_ended is not None, 5, "tracking ended")
        assert rot.status.tracking_ended == reason, rot.status.tracking_ended
        stops_before = len(md01.frames("stop"))
        rot.submit(Stop())
        md01.wait_for(lambda s: not s.is_moving, 5)  # stopped, not on its way to 300
        assert len(md01.frames("stop")) > stops_before  # the stop's bytes reached the rotor
        assert abs(md01.state().az_deg - 300.0) > 100.0
        assert len(opens) == 1, opens  # the port never closed
        assert rot.status.available
        assert [e for e in events if e.kind is ErrorKind.INTERNAL] == []
    finally:
        rot.stop()


@pytest.mark.parametrize(
    ("what", "wall", "track", "reason"),
    [
        ("a decayed TLE", TLE_EPOCH + 400 * DAY_S, decayed, "satellite orbit decayed"),
        ("past 2053", PAST_2053, lambda: None, "date beyond the ephemeris (2053)"),
    ],
)
def test_the_status_says_why_tracking_ended(
    what: str, wall: float, track: Callable[[], tuple[str, str, str] | None], reason: str
) -> None:
    tle = track()
    body = Body.satellite(*tle) if tle else Body.sun()
    with VirtualRotator("md01", sky=Sky(*BERLIN), wall_epoch_s=wall) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(body)
        v.run_for(5.0)
        assert v.status.tracking is None, what
        assert v.status.tracking_ended == reason
        assert v.errors(ErrorKind.INTERNAL) == []
        assert v.session.controller.link is not None


def test_a_part_that_raises_is_reset_and_reported_and_stops_still_go_out(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    def broken(_part: object, _scene: object) -> None:
        raise RuntimeError("a bug in auto-park")

    monkeypatch.setattr(autopark.AutoPark, "step", broken)
    park = {"park_az_deg": 0, "park_after_idle_s": 600}  # on: a part that is off is never run
    with VirtualRotator("md01", settings=park, emulator={"az_speed_deg_s": 5.0}) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        internal = v.errors(ErrorKind.INTERNAL)
        assert internal and "auto-park" in internal[0].message
        v.target(200.0)
        v.run_until(lambda h: h.truth().is_moving, 10, "turning")
        t = v.now
        v.stop()
        v.run_for(2.0)
        assert v.frames("stop", since=t), "the stop reached the controller"
        assert not v.truth().is_moving
        assert v.session.controller.link is not None


def test_a_part_reset_after_a_fault_runs_again_and_parks_after_a_new_quiet_spell(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The registry looks a part up on the session at every step: the new auto-park made by the
    reset is the one run (not the broken one), and its quiet spell starts at the reset."""
    real, calls = autopark.AutoPark.step, []

    def once_broken(part: autopark.AutoPark, scene: Any) -> Any:
        calls.append(scene.now)
        if len(calls) == 1:
            raise RuntimeError("a bug in auto-park, once")
        return real(part, scene)

    monkeypatch.setattr(autopark.AutoPark, "step", once_broken)
    park = {"park_az_deg": 0, "park_after_idle_s": 60}
    emulator = {"az_speed_deg_s": 5.0, "start_az_deg": 90}
    with VirtualRotator("md01", settings=park, emulator=emulator) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        reset_at = calls[0]
        assert "auto-park" in v.errors(ErrorKind.INTERNAL)[0].message
        v.run_until(lambda h: h.status.parked, 120, "parked by the new auto-park")
        parked_at = next(t for t, s in v.statuses if s.last_command_source == "auto-park")
        assert parked_at >= reset_at + 60.0  # a new quiet spell from the reset
        assert abs(v.truth().az_deg - 0.0) <= 0.5
