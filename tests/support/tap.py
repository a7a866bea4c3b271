"""The serial sniffer on a controller's transmit line, and small parsers of what a controller
reports, written from the protocol documents independently of bridge/protocols: the ground truth
that "the bridge published a bearing the controller did not report" is judged by (the fault suite,
the soak, a tapped ``Rig``). Garbage injected onto the line bypasses the tap: it is line noise,
not a report."""

from __future__ import annotations

import json
import re
import threading
import time
from pathlib import Path
from typing import Any

from bridge import emulators
from bridge.emulators.pty import EmulatedPort
from tests.support.mqtt import Message


class Tap:
    """Wraps a sans-IO responder; records every byte the controller transmits, with its time.

    It changes nothing: every call goes to the responder. It is the serial sniffer on the
    controller's TX line.
    """

    def __init__(self, device: Any) -> None:
        self._device = device
        self._lock = threading.Lock()
        self._sent = bytearray()

    def due_output(self, now: float) -> bytes:
        out = self._device.due_output(now)
        if out:
            with self._lock:
                self._sent += out
        return out

    def sent(self) -> bytes:
        with self._lock:
            return bytes(self._sent)

    def sent_since(self, offset: int) -> bytes:
        with self._lock:
            return bytes(self._sent[offset:])

    def sent_count(self) -> int:
        with self._lock:
            return len(self._sent)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._device, name)


_ROTOREZ_REPLY = re.compile(rb";(\d{3})")
_SATEL_AZ = re.compile(rb"Azimuth = (\d{1,3})")
_SATEL_EL = re.compile(rb"Elevation = (\d{1,3})")


def reported_positions(model: str, wire: bytes) -> tuple[set[float], set[float]]:
    """(azimuths, elevations) a controller of ``model`` put on the wire, from its own bytes.

    Written from the protocol documents, independently of bridge/protocols.
    """
    az: set[float] = set()
    el: set[float] = set()
    if model in ("rotorez", "rotorcard", "dcu1"):
        for m in _ROTOREZ_REPLY.finditer(wire):
            az.add(float(int(m.group(1)) % 360))
    elif model == "satel":
        az = {float(int(m.group(1))) for m in _SATEL_AZ.finditer(wire)}
        el = {float(int(m.group(1))) for m in _SATEL_EL.finditer(wire)}
    elif model == "rot1prog":
        for i in range(len(wire) - 4):
            f = wire[i : i + 5]
            if f[0] == 0x57 and f[4] == 0x20 and all(d <= 9 for d in f[1:4]):
                az.add(float(100 * f[1] + 10 * f[2] + f[3] - 360))
    else:  # rot2prog, md01: 57 H1 H2 H3 H4 PH V1 V2 V3 V4 PV 20, raw digits, tenths
        for i in range(len(wire) - 11):
            f = wire[i : i + 12]
            if f[0] != 0x57 or f[11] != 0x20 or any(d > 9 for d in f[1:5] + f[6:10]):
                continue
            az.add(round(100 * f[1] + 10 * f[2] + f[3] + f[4] / 10 - 360, 1))
            el.add(round(100 * f[6] + 10 * f[7] + f[8] + f[9] / 10 - 360, 1))
    return az, el


def _in(value: float, values: set[float], wraps: bool) -> bool:
    if any(abs(value - v) < 1e-6 for v in values):
        return True
    return wraps and any(abs((value % 360) - (v % 360)) < 1e-6 for v in values)


def start_emulator(model: str, link: Path, **options: Any) -> EmulatedPort[Any]:
    """An emulated controller on a fresh pty at ``link``, its transmit line tapped."""
    device = emulators.create(model, now=time.monotonic(), **options)
    return EmulatedPort(Tap(device), link=str(link), name=model)


def tap_of(emu: EmulatedPort[Any]) -> Tap:
    device = emu.device
    assert isinstance(device, Tap)
    return device


def bogus_bearings(
    model: str, emu: EmulatedPort[Any], messages: list[Message], root: str
) -> list[str]:
    """Published bearings/elevations the controller never reported (SatEL estimates excepted).

    Checks ``R/bearing`` and ``R/elevation`` (not for the SatEL, whose bearing topic also carries
    estimates) and the bearing/elevation of every ``R/status`` that is not marked estimated.
    """
    # the messages first: each one came from a reply already on the wire, while a rotor still
    # settling goes on replying and publishing after the snapshot of the wire is taken
    messages = list(messages)
    az, el = reported_positions(model, tap_of(emu).sent())
    # R/bearing is a true bearing (0..360, pointing.py); the controller's own value, which on a
    # SPID may be past 360 or below 0, is the status's raw_bearing
    wraps = True
    raw_wraps = model in ("rotorez", "rotorcard", "dcu1", "satel")
    bad: list[str] = []
    for m in messages:
        if m.topic == f"{root}/status":
            doc = json.loads(m.payload)
            if doc.get("estimated"):
                continue
            if doc.get("bearing") is not None and not _in(float(doc["bearing"]), az, wraps):
                bad.append(f"status bearing {doc['bearing']}")
            raw = doc.get("raw_bearing")
            if raw is not None and not _in(float(raw), az, raw_wraps):
                bad.append(f"status raw_bearing {raw}")
            if doc.get("elevation") is not None and not _in(float(doc["elevation"]), el, False):
                bad.append(f"status elevation {doc['elevation']}")
        elif m.topic == f"{root}/bearing" and model != "satel":
            if not _in(float(m.text), az, wraps):
                bad.append(f"bearing {m.text}")
        elif m.topic == f"{root}/elevation" and model != "satel":
            if not _in(float(m.text), el, False):
                bad.append(f"elevation {m.text}")
    return bad


def near_deg(a: float, b: float, tol: float, wraps: bool = True) -> bool:
    d = abs(a - b)
    if wraps:
        d %= 360
        d = min(d, 360 - d)
    return d <= tol
