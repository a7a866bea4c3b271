"""The fault suite's real parts: tests.support's Rig (a broker, emulated controllers on real ptys
with a wire tap, the bridge in-process; as its own process: tests.support.BridgeProcess) with the
fault suite's timings, and the ground truth the invariants are judged by.

Ground truth comes from two places the bridge never sees:
- the emulator's own state (where the rotor really is, which frames it obeyed), and
- a tap on the controller's transmit line (tests/support/tap.py): every byte the controller sent,
  parsed by small independent parsers (not the bridge's codecs), so "a bearing the controller
  did not report" can be checked exactly.

The soak runner (tests/soak) uses the same pieces.
"""

from __future__ import annotations

import json
import os
import random
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.emulators.spid_models import MOTION_OUTCOMES
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import ARRIVAL_TOL_DEG, Rig, Timings, arrival_tol
from tests.support.tap import (
    Tap,
    bogus_bearings,
    near_deg,
    reported_positions,
    start_emulator,
    tap_of,
)

__all__ = [  # what the suite's tests and the soak import from here
    "ARRIVAL_TOL_DEG",
    "AZEL",
    "FAST_BROKER_CONF",
    "ROTOREZ_FAMILY",
    "SPID",
    "LoginProbe",
    "Pki",
    "Rig",
    "Tap",
    "arrival_tol",
    "bogus_bearings",
    "cut_short",
    "fault_rig",
    "line_noise",
    "near_deg",
    "reported_positions",
    "start_emulator",
    "tap_of",
]

# -- timings -------------------------------------------------------------------------------------
# Scaled down like tests/support/rig.py's TEST_TIMINGS (same ratios as real hardware: the brake
# delay is much longer than a poll, a settle window longer than two polls), a little faster still.
EMU_FAST: dict[str, dict[str, Any]] = {
    "rotorez": {"speed_deg_s": 40.0, "brake_delay_s": 0.8, "jitter_deg": 1},
    "rotorcard": {"speed_deg_s": 40.0, "brake_delay_s": 0.0, "jitter_deg": 1},
    "dcu1": {"speed_deg_s": 40.0, "brake_delay_s": 0.8},
    "rot2prog": {"az_speed_deg_s": 30.0, "el_speed_deg_s": 15.0, "baud": 9600},
    "rot1prog": {"az_speed_deg_s": 30.0},
    "md01": {"az_speed_deg_s": 30.0, "el_speed_deg_s": 15.0},
    "satel": {"az_speed_deg_s": 30.0, "el_speed_deg_s": 15.0, "corrupt_on_misuse": True},
}
_ANALOG = {
    "idle_poll_interval_s": 0.25,
    "moving_poll_interval_s": 0.1,
    "settle_s": 0.4,
    "stall_timeout_s": 2.5,
    "silence_timeout_s": 1.0,
}
_DIGITAL = {
    "idle_poll_interval_s": 0.25,
    "moving_poll_interval_s": 0.1,
    "settle_s": 0.5,
    "stall_timeout_s": 4.0,
    "silence_timeout_s": 1.5,
}
BRIDGE_FAST: dict[str, dict[str, Any]] = {
    "rotorez": {**_ANALOG, "brake_delay_s": 0.8},
    "rotorcard": {**_ANALOG, "brake_delay_s": 0},
    "dcu1": {**_ANALOG, "brake_delay_s": 0.8},
    "rot2prog": {**_DIGITAL, "baud": 9600},
    "rot1prog": dict(_DIGITAL),
    "md01": dict(_DIGITAL),
    # a status report owed is given up after 2 s (SatelCodec): silence needs longer than that
    "satel": {**_DIGITAL, "silence_timeout_s": 3.0},
}
SPID = ("rot2prog", "rot1prog", "md01")
ROTOREZ_FAMILY = ("rotorez", "rotorcard", "dcu1")
AZEL = ("rot2prog", "md01", "satel")
# -- the rig: tests.support's, with tapped emulators and the fault suite's timings ---------------
FAULT_TIMINGS = Timings(emulator=EMU_FAST, bridge=BRIDGE_FAST)


def fault_rig(tmp_path: Path, broker: Mosquitto, probe: Probe) -> Rig:
    return Rig(tmp_path, broker, probe, timings=FAULT_TIMINGS, tapped=True)


@pytest.fixture
def rig(tmp_path: Path, broker: Mosquitto, probe: Probe) -> Iterator[Rig]:
    with fault_rig(tmp_path, broker, probe) as r:
        yield r


# -- invariants against the bridge's own status and the ground truth ----------------------------
def motion_frames(rig: Rig, rid: str) -> int:
    """Frames that made (or could have made) the rotor move, as the controller logged them."""
    model, emu = rig.models[rid], rig.emus[rid]
    if model in SPID:
        return len(emu.frames(*MOTION_OUTCOMES))
    if model == "satel":
        return len(emu.frames("slew"))
    return len(emu.frames(*BEARING_OUTCOMES))


def send_target(rig: Rig, rid: str, az: float, el: float) -> None:
    if rig.models[rid] in ("md01", "rot2prog", "satel"):
        rig.probe.publish(rig.topic(rid, "target"), f"{az:g} {el:g}")
    else:
        rig.probe.publish(rig.topic(rid, "target"), f"{az:g}")


def retained_matches_bridge(rig: Rig, rid: str, snap: dict[str, bytes]) -> bool:
    status = rig.status(rid)
    want = {
        "availability": b"online" if status.available else b"offline",
        "state": status.state.value.encode(),
    }
    if any(snap.get(rig.topic(rid, k)) != v for k, v in want.items()):
        return False
    doc = json.loads(snap.get(rig.topic(rid, "status"), b"{}"))
    if doc.get("bearing") != status.bearing_deg or doc.get("state") != status.state.value:
        return False
    if status.bearing_deg is not None and rig.models[rid] != "satel":
        return float(snap.get(rig.topic(rid, "bearing"), b"nan")) == status.bearing_deg
    return True


def assert_retained_matches_within_one_poll(rig: Rig, rids: list[str]) -> None:
    """The broker's retained state equals the bridge's own status within one (idle) poll on
    a quiet machine (a deadline: wait_until scales it on a busy one)."""
    poll_s = max(float(r["idle_poll_interval_s"]) for r in rig.rotators)

    def all_match() -> bool:
        snap = rig.retained()
        return all(retained_matches_bridge(rig, rid, snap) for rid in rids)

    wait_until(all_match, poll_s + 0.75, "retained state == the bridge's status")


def assert_bridge_matches_truth(rig: Rig, rid: str) -> None:
    """An idle rotor's published bearing is where the rotor really is."""
    status, truth = rig.status(rid), rig.emus[rid].state()
    model = rig.models[rid]
    assert not truth.is_moving
    assert status.bearing_deg is not None
    assert near_deg(status.bearing_deg, truth.az_deg, 2.5), (status, truth)  # a true bearing
    if model in SPID:  # the controller's own value says which side of the overlap
        assert status.raw_bearing_deg is not None
        assert near_deg(status.raw_bearing_deg, truth.az_deg, 2.5, False), (status, truth)


# -- line noise and replies cut short ----------------------------------------------------------
BOARD_BYTES = b" .0123456789;\xe0ABCDEFGHIJKLMNOPQRSTUVWXYZ"  # what a Rotor-EZ may transmit
NOT_ON_A_ROTOREZ_LINE = bytes(b for b in range(256) if b not in BOARD_BYTES)
NOT_IN_A_SPID_FRAME = bytes(b for b in range(256) if b not in b"W :" and not 0x30 <= b <= 0x39)


def line_noise(rng: random.Random, model: str) -> bytes:
    """Random noise that can be told from a reply: it starts with a byte the controller never
    sends (Rotor-EZ family), cannot start or end a SPID frame, or is a line of its own (SatEL;
    noise glued to a report line is test_serial.py::test_noise_byte_during_a_satel_slew_...)."""
    n = rng.randint(1, 24)
    if model in ROTOREZ_FAMILY:
        return bytes([rng.choice(NOT_ON_A_ROTOREZ_LINE)]) + rng.randbytes(n)
    if model in SPID:
        return bytes(rng.choice(NOT_IN_A_SPID_FRAME) for _ in range(n))
    return bytes(rng.choice(b"\x00\x07\xffqwerty=%!?") for _ in range(n)) + b"\r\n"


def after_transmission(emu: Any, timeout_s: float = 5.0) -> None:
    """Wait until the controller has sent something more and its transmitter is idle again."""
    n = tap_of(emu).sent_count()
    emu.wait_until(
        lambda d, now: (d.sent_count(), d._tx.pending()),  # the emulator's UART queue
        lambda v: v[0] > n and v[1] == 0,
        timeout_s,
    )


def cut_short(rng: random.Random, model: str, emu: Any) -> bytes:
    """A reply cut short by a flaky adapter (a value the rotor is not at)."""
    if model in ROTOREZ_FAMILY:
        return b";3" if rng.random() < 0.5 else b";33"
    if model in SPID:
        # the start of the controller's own last frame (so no splice can make up a value)
        wire = tap_of(emu).sent()
        last = wire.rfind(b"\x57", 0, len(wire) - 11)
        return wire[last : last + rng.randint(1, 11)]
    return (
        b"Motion ENABLED\r\nMode 0 - azimuth break at NORTH\r\nTime: 2026/01/01 00:00:00\r\n"
        b"Azimuth = 333     Absolute = 333\r\n"
    )


# -- a certificate authority, made at test time (never committed) --------------------------------
class Pki:
    """A CA, a server certificate for 127.0.0.1 and a client certificate, made with openssl."""

    def __init__(self, directory: Path) -> None:
        self.dir = directory
        directory.mkdir(parents=True, exist_ok=True)
        ec = ["-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes"]
        self._sh("req", "-x509", *ec, "-keyout", "ca.key", "-out", "ca.crt", "-days", "2",
                 "-subj", "/CN=rotor-bridge test CA")  # fmt: skip
        self._sh("req", "-x509", *ec, "-keyout", "rogue-ca.key", "-out", "rogue-ca.crt",
                 "-days", "2", "-subj", "/CN=some other CA")  # fmt: skip
        for name, san in (
            ("server", "subjectAltName=IP:127.0.0.1,DNS:localhost"),
            ("client", "subjectAltName=DNS:rotor-bridge"),
        ):
            self._sh("req", *ec, "-keyout", f"{name}.key", "-out", f"{name}.csr",
                     "-subj", f"/CN={name}")  # fmt: skip
            (directory / f"{name}.ext").write_text(san + "\n")
            self._sh("x509", "-req", "-in", f"{name}.csr", "-CA", "ca.crt", "-CAkey", "ca.key",
                     "-CAcreateserial", "-out", f"{name}.crt", "-days", "2",
                     "-extfile", f"{name}.ext")  # fmt: skip
        for key in directory.glob("*.key"):
            os.chmod(key, 0o600)

    def _sh(self, *args: str) -> None:
        subprocess.run(["openssl", *args], cwd=self.dir, check=True, capture_output=True)

    def path(self, name: str) -> Path:
        return self.dir / name


def mosquitto_password_file(path: Path, users: dict[str, str]) -> Path:
    path.unlink(missing_ok=True)
    for i, (user, password) in enumerate(users.items()):
        flags = ["-c"] if i == 0 else []
        subprocess.run(
            ["mosquitto_passwd", "-b", *flags, str(path), user, password],
            check=True,
            capture_output=True,
        )
    return path


# -- a broker without Nagle's 40 ms -------------------------------------------------------------
# Small MQTT packets on loopback otherwise wait for a delayed TCP ACK (about 40 ms a round trip);
# with thousands of round trips that is most of the suite's time. Production is unaffected.
# (tests.support.Probe sets TCP_NODELAY on its side.)
FAST_BROKER_CONF = "allow_anonymous true\nset_tcp_nodelay true"


@pytest.fixture
def broker_conf() -> str:
    return FAST_BROKER_CONF


def LoginProbe(  # noqa: N802  (reads like the class it makes)
    port: int, *, username: str, password: str, pki: Pki | None = None, topic_filter: str = "#"
) -> Probe:
    """A probe that logs in, and with ``pki`` speaks TLS with our client certificate."""
    tls = None
    if pki is not None:
        tls = {
            "ca_certs": str(pki.path("ca.crt")),
            "certfile": str(pki.path("client.crt")),
            "keyfile": str(pki.path("client.key")),
        }
    return Probe(port, topic_filter, username=username, password=password, tls=tls)
