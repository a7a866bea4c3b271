"""A rig: a private mosquitto, emulated controllers on real ptys (opened by the bridge through a
stable link, like /dev/serial/by-id/...), and the bridge itself in-process, all real parts.
The fault suite's Rig (tests/faults/conftest.py) is this one with tapped emulators."""

from __future__ import annotations

from pathlib import Path
from types import TracebackType
from typing import Any

from bridge import emulators
from bridge.app import App
from bridge.emulators.pty import EmulatedPort
from bridge.mosquitto import Mosquitto
from bridge.settings import Settings
from tests.support.mqtt import Probe, retained_snapshot

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
FAST_SPID_BRIDGE = {
    "idle_poll_interval_s": 0.5,
    "moving_poll_interval_s": 0.1,
    "settle_s": 1.0,
    "stall_timeout_s": 4.0,
    "silence_timeout_s": 2.0,
}


class Rig:
    def __init__(self, tmp_path: Path, broker: Mosquitto, probe: Probe) -> None:
        self.tmp = tmp_path
        self.broker = broker
        self.probe = probe
        self.emus: dict[str, EmulatedPort[Any]] = {}
        self.models: dict[str, str] = {}
        self.rotators: list[dict[str, Any]] = []
        self.app: App | None = None
        self.base = "rotor"
        self.mqtt_extra: dict[str, Any] = {}  # e.g. TLS or credentials

    def add(
        self, rid: str, model: str = "rotorez", emu: dict | None = None, **bridge: Any
    ) -> EmulatedPort[Any]:
        link = self.tmp / f"serial-by-id-{rid}"
        spid = model in ("rot2prog", "rot1prog", "md01", "satel")
        fast = FAST_SATEL if model == "satel" else FAST_SPID if spid else FAST_ROTOR
        emu_options = {**fast, **(emu or {})}
        if model == "rotorcard":
            emu_options["brake_delay_s"] = 0.0  # Yaesu rotors have no brake
        port = emulators.start(model, link=str(link), **emu_options)
        self.emus[rid] = port
        self.models[rid] = model
        cfg = {
            "id": rid,
            "model": model,
            "port": str(link),
            **(FAST_SPID_BRIDGE if spid else FAST_BRIDGE),
        }
        if model == "rotorcard":
            cfg["brake_delay_s"] = 0
        cfg.update(bridge)
        self.rotators.append(cfg)
        return port

    @property
    def settings(self) -> Settings:
        return Settings(
            mqtt={
                "host": "127.0.0.1",
                "port": self.broker.port,
                "base_topic": self.base,
                "client_id": f"bridge-under-test-{id(self)}",
                **self.mqtt_extra,
            },
            rotators=self.rotators,
            state_file=self.tmp / "state.json",
        )

    def start(self) -> App:
        self.app = App(self.settings)
        self.app.start()
        return self.app

    def stop(self) -> None:
        if self.app is not None:
            self.app.stop()
            self.app = None

    def root(self, rid: str) -> str:
        return self.base if len(self.rotators) == 1 else f"{self.base}/{rid}"

    def topic(self, rid: str, leaf: str) -> str:
        return f"{self.root(rid)}/{leaf}"

    def ready(self, rid: str, timeout_s: float = 10.0, after: float | None = None) -> None:
        """Online and settled: idle, past the start-up brake window (``unknown`` for a DCU-1,
        which cannot report)."""
        settled = "unknown" if self.models[rid] == "dcu1" else "idle"
        self.probe.wait_value(self.topic(rid, "availability"), "online", timeout_s, after)
        self.probe.wait_value(self.topic(rid, "state"), settled, timeout_s, after)

    def retained(self) -> dict[str, bytes]:
        return retained_snapshot(self.broker.port, f"{self.base}/#")

    def close(self) -> None:
        self.stop()
        for emu in self.emus.values():
            emu.close()

    def __enter__(self) -> Rig:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()
