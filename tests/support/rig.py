"""The rig, one for the tests, the fault suite and the benchmarks: a broker, emulated controllers
on real ptys (opened by the bridge through a stable link, like /dev/serial/by-id/...), an MQTT
probe, and the bridge itself, in-process (``start``) or as its own service process
(``start_process``), all real parts.

What differs between its users is configuration, not code:
- ``timings``: the emulators' and the bridge's options for each model (``TEST_TIMINGS`` scaled
  down so a test takes seconds; the fault suite's faster still; ``REAL_TIMINGS``, the defaults,
  for the benchmarks);
- ``open_line``: how a controller is put on a line (the default: an emulator at
  ``tmp/serial-by-id-<id>``, its transmit line tapped with ``tapped=True``; the benchmarks' adds
  a frame log, a byte counter and a paced relay);
- ``scope``: what closes everything it opened (its own, or the benchmarks' Scope), and ``spawn``:
  how the service process is started.

Rules:
1. ``close()`` (or leaving the ``with`` block) stops the bridge first, then closes what the scope
   holds, in reverse order: the emulators, and whatever a caller put there.
2. A rig with one rotator publishes under the base topic, with several under ``base/<id>``
   (``topic``); ``t(leaf)`` is the one rotator's topic, ``t(id, leaf)`` any rotator's.
3. A rotator not ready in time says why it may not be: its errors, and for a bridge process
   whether it runs and the end of its log (a fixture that failed under load said only that
   ``online`` never came).
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any, Protocol

from bridge import emulators
from bridge.app import App
from bridge.emulators.pty import EmulatedPort
from bridge.settings import Settings
from tests.support.mqtt import Probe, retained_snapshot
from tests.support.process import BridgeProcess, Spawn, bridge_config
from tests.support.process import _spawn as _default_spawn
from tests.support.tap import bogus_bearings, near_deg, start_emulator
from tests.support.waiting import slow

# R/error's kinds that are the controller's line speaking (bytes that are no reply, the port
# lost or not there): never the answer to a command, and free to come at any moment
LINE_WORDS = ("protocol", "serial")

# Timings scaled down so a test takes seconds, with the same ratios as real hardware:
# the controller's brake delay is still much longer than a poll, a settle window, a reply.
FAST_ROTOR = {"speed_deg_s": 40.0, "brake_delay_s": 1.5, "jitter_deg": 1}
FAST_POLLING = {
    "idle_poll_interval_s": 0.3,
    "moving_poll_interval_s": 0.1,
    "settle_s": 0.6,
    "stall_timeout_s": 2.5,
    "silence_timeout_s": 1.0,
}
FAST_BRIDGE = {**FAST_POLLING, "brake_delay_s": 1.5}

# SPID: digital encoders (no jitter), no brake, a slow line (600 baud: 0.42 s per exchange)
FAST_SPID = {"az_speed_deg_s": 30.0, "el_speed_deg_s": 15.0}
FAST_SATEL = {"az_speed_deg_s": 20.0, "el_speed_deg_s": 10.0, "corrupt_on_misuse": True}
# GS-232: a potentiometer read in whole degrees, no brake, a fast line (9600 baud)
FAST_GS232 = {"az_speed_deg_s": 20.0, "el_speed_deg_s": 10.0}
GS232_MODELS = (
    "gs232a",
    "gs232b",
    "gs232a-az",
    "gs232b-az",
    "gs232a-450",
    "gs232b-450",
    "gs232a-az-450",
    "gs232b-az-450",
)
# Easycomm: steppers or encoders read in tenths, no brake, a fast line (19200 baud)
FAST_EASYCOMM = {"az_speed_deg_s": 20.0, "el_speed_deg_s": 10.0}
EASYCOMM_MODELS = tuple(f"easycomm{v}{s}" for v in (2, 3) for s in ("", "-az", "-separate"))
# RT-21: a potentiometer read in tenths, its own brake handling, 4800 baud
FAST_RT21 = {"az_speed_deg_s": 20.0}
# RC2800: potentiometers read in tenths, no brake, 9600 baud, 200 ms between its two axes
FAST_RC2800 = {"az_speed_deg_s": 20.0, "el_speed_deg_s": 10.0}
RC2800_MODELS = ("rc2800", "rc2800-az")
# Prosistel: a D (whole degrees) or a Combi-Track (tenths, two units), 9600 baud, own brakes
FAST_PROSISTEL = {"az_speed_deg_s": 20.0, "el_speed_deg_s": 10.0}
PROSISTEL_MODELS = ("prosistel", "prosistel-el", "prosistel-el-a", "prosistel-combi")
FAST_SPID_BRIDGE = {
    "idle_poll_interval_s": 0.5,
    "moving_poll_interval_s": 0.1,
    "settle_s": 1.0,
    "stall_timeout_s": 4.0,
    "silence_timeout_s": 2.0,
}

# ground-truth tolerance for "the rotor is there": emulator jitter + the bridge's tolerance
ARRIVAL_TOL_DEG = {"rotorez": 3.5, "rotorcard": 3.5, "dcu1": 3.5, "satel": 1.5}


def arrival_tol(model: str) -> float:
    return ARRIVAL_TOL_DEG.get(model, 1.0)


@dataclass(frozen=True)
class Timings:
    """Options for each model: ``emulator`` to the emulated controller, ``bridge`` to the
    rotator's configuration (a model not named gets none: its defaults)."""

    emulator: Mapping[str, Mapping[str, Any]]
    bridge: Mapping[str, Mapping[str, Any]]


_NO_BRAKE = {"brake_delay_s": 0.0}  # Yaesu rotors have no brake
TEST_TIMINGS = Timings(
    emulator={
        "rotorez": FAST_ROTOR,
        "dcu1": FAST_ROTOR,
        "rotorcard": {**FAST_ROTOR, **_NO_BRAKE},
        "rot2prog": FAST_SPID,
        "rot1prog": FAST_SPID,
        "md01": FAST_SPID,
        "satel": FAST_SATEL,
        **dict.fromkeys(GS232_MODELS, FAST_GS232),
        **dict.fromkeys(EASYCOMM_MODELS, FAST_EASYCOMM),
        "rt21": FAST_RT21,
        **dict.fromkeys(RC2800_MODELS, FAST_RC2800),
        **dict.fromkeys(PROSISTEL_MODELS, FAST_PROSISTEL),
    },
    bridge={
        "rotorez": FAST_BRIDGE,
        "dcu1": FAST_BRIDGE,
        "rotorcard": {**FAST_BRIDGE, "brake_delay_s": 0},
        "rot2prog": FAST_SPID_BRIDGE,
        "rot1prog": FAST_SPID_BRIDGE,
        "md01": FAST_SPID_BRIDGE,
        "satel": FAST_SPID_BRIDGE,
        **dict.fromkeys(GS232_MODELS, FAST_POLLING),
        **dict.fromkeys(EASYCOMM_MODELS, FAST_POLLING),
        "rt21": FAST_POLLING,
        **dict.fromkeys(RC2800_MODELS, FAST_POLLING),
        **dict.fromkeys(PROSISTEL_MODELS, FAST_POLLING),
    },
)
REAL_TIMINGS = Timings(emulator={}, bridge={})


class Broker(Protocol):
    """What the rig needs of a broker: ``tests.support.mosquitto.Mosquitto``, or the benchmarks'."""

    port: int


@dataclass
class Line:
    """One emulated controller and the path the bridge opens for it; the benchmarks' lines also
    keep the controller's frame log, a byte counter and the paced relay in front of it."""

    id: str
    model: str
    emu: EmulatedPort[Any]
    path: Path
    frames: Any = None
    counter: Any = None
    relay: Any = None


#: (rig, rotator id, model, emulator options) -> the line, its closing put on ``rig.scope``
OpenLine = Callable[["Rig", str, str, dict[str, Any]], Line]


def emulator_line(rig: Rig, rid: str, model: str, options: dict[str, Any]) -> Line:
    """An emulator on a fresh pty at ``tmp/serial-by-id-<id>`` (tapped if the rig says so)."""
    link = rig.tmp / f"serial-by-id-{rid}"
    if rig.tapped:
        emu = start_emulator(model, link, **options)
    else:
        emu = emulators.start(model, link=str(link), **options)
    rig.scope.callback(emu.close)
    return Line(rid, model, emu, link)


class Rig:
    #: the stop express (interfaces/mqtt/express.py), a Python process of its own beside each
    #: bridge the rig starts (about 0.4 CPU-s each, most of a rig test's cost): on where it is
    #: what a test is about (tests/integration/test_stop_express.py, the broker matrix;
    #: tests/mqtt/test_express.py proves it on its own), off elsewhere: the stop lane then
    #: carries the stops, as with ``mqtt.stop_express`` off; ``mqtt_extra`` may say otherwise.
    #: None leaves the key out: the bridge's own default (the benchmarks, whose older engines
    #: know no such key)
    express: bool | None = False

    def __init__(
        self,
        tmp_path: Path,
        broker: Broker,
        probe: Probe,
        *,
        timings: Timings = TEST_TIMINGS,
        tapped: bool = False,
        open_line: OpenLine = emulator_line,
        scope: contextlib.ExitStack | None = None,
        spawn: Spawn = _default_spawn,
    ) -> None:
        self.tmp = tmp_path
        self.broker = broker
        self.probe = probe
        self.timings = timings
        self.tapped = tapped
        self.open_line = open_line
        self.scope = scope if scope is not None else contextlib.ExitStack()
        self.spawn = spawn
        self.lines: dict[str, Line] = {}
        self.rotators: list[dict[str, Any]] = []
        self.app: App | None = None
        self.bridge: BridgeProcess | None = None
        self.base = "rotor"
        self.mqtt_extra: dict[str, Any] = {}  # e.g. TLS or credentials
        self.sections: dict[str, Any] = {}  # more of the configuration (homeassistant, station)
        # the in-process bridge's wall clock (App's ``wall``): a DX cluster test's spots are of
        # a fixed time (tests/support/clock.py RunningWall); None: the host's
        self.wall: Callable[[], float] | None = None

    def add(
        self, rid: str, model: str = "rotorez", emu: dict[str, Any] | None = None, **bridge: Any
    ) -> EmulatedPort[Any]:
        """A controller of ``model`` on its line, and a rotator of the bridge on it: ``emu``
        options to the controller, ``bridge`` to the rotator (over the rig's timings)."""
        options = {**self.timings.emulator.get(model, {}), **(emu or {})}
        line = self.open_line(self, rid, model, options)
        self.lines[rid] = line
        self.rotators.append(
            {
                "id": rid,
                "model": model,
                "port": str(line.path),
                **self.timings.bridge.get(model, {}),
                **bridge,
            }
        )
        return line.emu

    @property
    def emus(self) -> dict[str, EmulatedPort[Any]]:
        return {rid: line.emu for rid, line in self.lines.items()}

    @property
    def models(self) -> dict[str, str]:
        return {rid: line.model for rid, line in self.lines.items()}

    def config(self) -> dict[str, Any]:
        """The bridge's configuration, as the tables of its TOML file."""
        return bridge_config(
            self.tmp,
            self.broker.port,
            self.rotators,
            client_id=f"bridge-under-test-{os.getpid()}-{id(self)}",
            base_topic=self.base,
            mqtt={
                **({} if self.express is None else {"stop_express": self.express}),
                **self.mqtt_extra,
            },
            sections=self.sections,
        )

    @property
    def settings(self) -> Settings:
        return Settings(**self.config())

    def start(self) -> App:
        """The bridge in this process."""
        self.app = App(self.settings, wall=self.wall or time.time)
        self.app.start()
        return self.app

    def start_process(
        self, *, log_level: str | None = "DEBUG", error: type[Exception] = AssertionError
    ) -> BridgeProcess:
        """The bridge as its own service process (``python -m bridge run -c FILE``)."""
        self.bridge = BridgeProcess(
            self.tmp, self.config(), log_level=log_level, spawn=self.spawn, error=error
        ).start()
        return self.bridge

    def stop(self) -> None:
        if self.app is not None:
            self.app.stop()
            self.app = None
        if self.bridge is not None:
            if self.bridge.alive():
                self.bridge.terminate()
            self.bridge = None

    # -- topics -----------------------------------------------------------------------------
    def root(self, rid: str) -> str:
        return self.base if len(self.rotators) == 1 else f"{self.base}/{rid}"

    def topic(self, rid: str, leaf: str) -> str:
        return f"{self.root(rid)}/{leaf}"

    def t(self, *where: str) -> str:
        """``t(leaf)``: the one rotator's topic; ``t(id, leaf)``: that rotator's."""
        rid, leaf = (self.line.id, where[0]) if len(where) == 1 else where
        return self.topic(rid, leaf)

    # -- the one rotator of a rig that has one ----------------------------------------------
    @property
    def line(self) -> Line:
        assert len(self.lines) == 1, f"the rig has {len(self.lines)} rotators, not one"
        return next(iter(self.lines.values()))

    @property
    def emu(self) -> EmulatedPort[Any]:
        return self.line.emu

    @property
    def model(self) -> str:
        return self.line.model

    @property
    def frames(self) -> Any:
        return self.line.frames

    @property
    def counter(self) -> Any:
        return self.line.counter

    @property
    def relay(self) -> Any:
        return self.line.relay

    @property
    def mqtt(self) -> Probe:
        """The probe, by the benchmarks' name for it."""
        return self.probe

    @property
    def broker_port(self) -> int:
        return self.broker.port

    # -- what a test waits for and judges ---------------------------------------------------
    ready_s = 10.0  # how long ``ready`` waits unless told: a broker may take longer to join

    def ready(self, rid: str, timeout_s: float | None = None, after: float | None = None) -> None:
        """Online and settled: idle, past the start-up brake window (``unknown`` for a DCU-1,
        which cannot report)."""
        timeout_s = self.ready_s if timeout_s is None else timeout_s
        settled = "unknown" if self.models[rid] == "dcu1" else "idle"
        error = self.probe.timeout_error
        try:
            self.probe.wait_value(self.topic(rid, "availability"), "online", timeout_s, after)
            self.probe.wait_value(self.topic(rid, "state"), settled, timeout_s, after)
        except error as exc:  # rule 3
            raise error(f"{exc}\n{self.why_not_ready(rid)}") from None

    def why_not_ready(self, rid: str) -> str:
        """Rule 3: what the bridge said of ``rid`` (its error topic), and, for a bridge process,
        whether it still runs and the end of its log."""
        errors = [m.text for m in self.probe.on(self.topic(rid, "error"))]
        said = f"{rid}'s errors: {errors[-10:]}"
        bridge = self.bridge
        if bridge is None:
            return said  # (an in-process bridge's log is the test's captured log)
        running = "runs" if bridge.alive() else f"exited with {bridge.proc and bridge.proc.poll()}"
        return f"{said}\nthe bridge process {running}; the end of its log:\n{bridge.log()[-4000:]}"

    def retained(self) -> dict[str, bytes]:
        return retained_snapshot(self.broker.port, f"{self.base}/#")

    def refused(self, rid: str, payload: str, leaf: str = "target") -> str:
        """Publish ``payload`` on ``rid``'s ``leaf`` topic; the message of the refusal the bridge
        reports for it on the error topic."""
        t = time.monotonic()
        self.probe.publish(self.topic(rid, leaf), payload)
        err = json.loads(  # the first R/error after it that is no word of the line's (junk
            self.probe.wait_for(  # a restart found on the wire, a reopen's failure: they
                self.topic(rid, "error"),  # answer no command, and a loaded host may put
                lambda m: json.loads(m.payload)["kind"] not in LINE_WORDS,  # one first)
                after=t,
            ).payload
        )
        assert err["kind"] == "refused", err
        return str(err["message"])

    def unplug_and_replug(self, rid: str) -> None:
        """Yank ``rid``'s adapter and wait for ``offline``; plug it back (the controller
        power-cycled with it) and wait for ``online``."""
        emu, availability = self.emus[rid], self.topic(rid, "availability")
        t = time.monotonic()
        emu.unplug()
        self.probe.wait_value(availability, "offline", after=t)
        t = time.monotonic()
        emu.replug()
        self.probe.wait_value(availability, "online", timeout_s=15, after=t)

    def junk_reported(self, rid: str, *junk: bytes, polls: int = 4) -> None:
        """Put ``junk`` on ``rid``'s line towards the bridge; wait for the protocol error it
        reports, then for ``polls`` more questions to the controller (the readings after it)."""
        emu = self.emus[rid]
        t = time.monotonic()
        for data in junk:
            emu.inject(data)
        err = json.loads(self.probe.wait_for(self.topic(rid, "error"), after=t).payload)
        assert err["kind"] == "protocol" and "no valid reply" in err["message"], err
        n = len(emu.frames("query"))
        emu.wait_until(lambda d, now: len(d.frames("query")), lambda k: k >= n + polls, 15)

    def status(self, rid: str) -> Any:
        """The in-process bridge's own status of rotator ``rid``."""
        assert self.app is not None
        return next(r for r in self.app.rotators if r.id == rid).status

    def arrived(self, rid: str, az: float, el: float | None = None, timeout_s: float = 20) -> None:
        """Wait until the rotor really points at az (/el), still (the emulator's truth).

        Azimuth is compared as a direction: a SPID may reach true 200 at raw -160, the side
        that needs the least travel, which is what the bridge picks when it is already there.
        """
        model, emu = self.models[rid], self.emus[rid]
        tol = arrival_tol(model)

        def there(s: Any) -> bool:
            if s.is_moving or s.in_brake_delay:
                return False
            if not near_deg(s.az_deg, az, tol):
                return False
            return el is None or abs(s.el_deg - el) <= tol

        emu.wait_for(there, slow(timeout_s))

    def bogus(self, rid: str) -> list[str]:
        """Bearings the bridge published that the controller never reported (a tapped rig)."""
        return bogus_bearings(self.models[rid], self.emus[rid], self.probe.messages, self.root(rid))

    # -- the end ----------------------------------------------------------------------------
    def close(self) -> None:
        self.stop()
        self.scope.close()

    def __enter__(self) -> Rig:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()
