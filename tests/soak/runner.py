"""Soak run: the real bridge process, six emulated controllers, a real mosquitto, random faults
on all of them at once for ``--minutes`` (10 by default), every invariant checked continuously.

    python -m tests.soak --minutes 10        # the full run (docs/reliability.md has a table)
    python -m tests.soak --minutes 1.5       # a short try

Not a pytest module (pytest collects test_*.py only). Exit status 0 when every invariant held.

What it does: one bridge process (`python -m bridge run -c FILE`) with a Rotor-EZ, a RotorCard, a
DCU-1, a Rot2Prog (600 baud), an MD-01 and a SatEL, each on its own pty with its transmit line
tapped. The runner sends random valid targets, and injects faults at random: the broker killed
(or stopped) and restarted without persistence, adapters unplugged and replugged (with or
without the controller losing power), controllers silent, line noise and replies cut short
between replies, controller power cycles, and commands that must be refused (retained, while
offline, while locked, out of the limits, unreadable).

Invariants (a violation makes the exit status 1):
- no bearing published that the controller did not report (checked on every message against
  the wire tap; SatEL estimates, marked "estimated" in R/status, excepted);
- no motion from a refused, retained or stale command (every target frame the controllers
  received is audited: it must be a command the runner had accepted, sent after the last fault
  that dropped pending commands, never one of the "poison" values refused commands carry);
- the rotor ends where the last accepted command asked: a target accepted while everything was
  up must be reached (ground truth), unless a newer one replaced it or a serial fault on that
  rotator interrupted it; one that is neither reached nor excused is a lost command;
- after every recovery the retained state on the broker matches the truth (availability,
  bearing) within one poll of the bridge being back;
- the bridge process never exits on its own, and its memory stays bounded.
"""

from __future__ import annotations

import argparse
import json
import math
import random
import statistics
import sys
import tempfile
import threading
import time
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bridge.emulators import as_built
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from tests.faults.conftest import (
    ROTOREZ_FAMILY,
    SPID,
    Tap,
    cut_short,
    line_noise,
    near_deg,
    reported_positions,
    start_emulator,
    tap_of,
)
from tests.support import BridgeProcess
from tests.support import Probe as FastProbe
from tests.support import retained_snapshot as fast_retained
from tests.support.mosquitto import Mosquitto, free_port
from tests.support.waiting import slow

# id: (model, emulator options, bridge options). Rotor speeds are faster than real rotators so
# ten minutes hold many moves; the SatEL's are told to the bridge (it bounds a silent slew by
# them, as a user with a faster rotor would set them); every other timing is the default.
# the slow lines' default idle poll (Rot2Prog 9.3 s, SatEL 3.9 s) and silence timeout are longer;
# the soak's timing (IDLE_POLL_S, offline 3 s into a silence) is the fast lines' defaults
_TIMING = {"idle_poll_interval_s": 1.0, "silence_timeout_s": 3.0}
ROTATORS: dict[str, tuple[str, dict[str, Any], dict[str, Any]]] = {
    "ez": ("rotorez", {"speed_deg_s": 20.0, "brake_delay_s": 2.0, "jitter_deg": 1},
           {"brake_delay_s": 2.0}),
    "card": ("rotorcard", {"speed_deg_s": 20.0, "brake_delay_s": 0.0, "jitter_deg": 1}, {}),
    "dcu": ("dcu1", {"speed_deg_s": 6.0, "brake_delay_s": 2.0}, {"brake_delay_s": 2.0}),
    "spid": ("rot2prog", {"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0}, dict(_TIMING)),
    "md": ("md01", {"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0}, {}),
    "sat": ("satel", {"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0},
            {"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0, **_TIMING}),
}  # fmt: skip
AZEL = ("rot2prog", "md01", "satel")
IDLE_POLL_S = 1.0  # the idle poll every rotator here has: "within one poll"
SATEL_STOP_REPORT_S = 2.0  # after a stop the SatEL reports within its reply time, or never
RECOVERY_SLACK_S = 1.0  # a fresh retained snapshot is itself a broker round trip or two
# R/state in which a rotator is sent its next target (docs/mqtt.md, what the states mean). A
# fresh bridge shows one of READY; `stalled` is one too: the bridge stopped the rotor and said
# "send the target again" (a Rot2Prog or MD-01 power-cycled mid-turn forgets its target and has
# no power-on byte to say so), and it stays stalled until the next command, as a user would send
READY = (b"idle", b"unknown", b"moving", b"braking")
COMMANDABLE = (*READY, b"stalled")


def reaches(model: str, az: float, el: float | None) -> tuple[float, float | None]:
    """Where a target takes the rotor: a SatEL's rotors stop at ten-degree steps as built, and
    it is sent the nearest (protocols/satel.py rule 7: 125/35 goes out as 130/40)."""
    if model != "satel":
        return az, el
    return math.floor(az / 10 + 0.5) * 10.0, None if el is None else math.floor(
        el / 10 + 0.5
    ) * 10.0


def is_poison(model: str, az: float, el: float | None) -> bool:
    """Refused commands carry azimuths = 2 (mod 5); accepted ones multiples of 5. A SatEL is
    sent its ten-degree steps whatever it is asked, so there its elevation tells them apart:
    refused commands carry 30, accepted ones multiples of 20."""
    if model == "satel":
        return el is not None and abs((el % 20.0) - 10.0) < 0.6
    return abs((az % 5) - 2) < 0.6


@dataclass
class Expectation:
    az: float
    el: float | None
    t0: float
    deadline: float
    payload: str
    outcome: str | None = None
    t_done: float | None = None


@dataclass
class Fault:
    kind: str
    t_start: float
    t_end: float
    during_motion: bool
    power_cycle: bool = False
    left: int = 0  # injections still to do (noise)
    next_t: float = 0.0


@dataclass
class Rot:
    rid: str
    model: str
    emu: Any
    speed: float
    reported_az: set[float] = field(default_factory=set)
    reported_el: set[float] = field(default_factory=set)
    tap_offset: int = 0
    tap_lock: threading.Lock = field(default_factory=threading.Lock)
    accepted: list[tuple[float, float, float | None]] = field(default_factory=list)
    expectation: Expectation | None = None
    fault: Fault | None = None
    recovering: tuple[str, float] | None = None  # (kind, t_end)
    why: str = ""  # why the retained state did not match yet while recovering
    last_interrupt_t: float = -1e9  # a fault that may stop the rotor or drop its command
    stale_at: list[float] = field(default_factory=list)  # the link went down at these times
    next_fault: float = 0.0
    next_cmd: float = 0.0
    frames_seen: int = 0

    @property
    def tap(self) -> Tap:
        return tap_of(self.emu)

    def update_reported(self) -> None:
        with self.tap_lock:
            start = max(0, self.tap_offset - 48)  # re-read a frame or line cut at the end
            data = self.tap.sent_since(start)
            az, el = reported_positions(self.model, data)
            self.reported_az |= az
            self.reported_el |= el
            self.tap_offset = start + len(data)

    def was_reported(self, value: float, axis: str, raw: bool = False) -> bool:
        """``value`` (a published true bearing, or with ``raw`` the controller's own value)
        is one the controller reported."""
        wraps = not raw or self.model not in SPID
        for attempt in range(2):
            values = self.reported_az if axis == "az" else self.reported_el
            if any(near_deg(value, v, 1e-6, wraps and axis == "az") for v in values):
                return True
            if attempt == 0:
                self.update_reported()
        return False


class Monitor(FastProbe):
    """Subscribed to everything; checks every bearing as it arrives, keeps the latest state."""

    def __init__(self, port: int, soak: Soak) -> None:
        self.soak = soak
        self.latest: dict[str, tuple[float, bytes]] = {}
        self.errors: dict[str, list[tuple[float, dict[str, Any]]]] = defaultdict(list)
        self.count = 0
        self.lock = threading.Lock()
        super().__init__(port, "#")

    def _on_message(self, client, userdata, msg) -> None:  # noqa: ANN001
        now = time.monotonic()
        topic, payload = msg.topic, bytes(msg.payload)
        with self.lock:
            self.count += 1
            self.latest[topic] = (now, payload)
        parts = topic.split("/")
        if len(parts) < 3 or parts[0] != "rotor" or parts[1] not in self.soak.rots:
            return
        rot, leaf = self.soak.rots[parts[1]], "/".join(parts[2:])
        try:
            if leaf == "error":
                with self.lock:
                    self.errors[rot.rid].append((now, json.loads(payload)))
            elif leaf in ("bearing", "elevation") and rot.model != "satel" and payload:
                axis = "az" if leaf == "bearing" else "el"
                if not rot.was_reported(float(payload), axis):
                    self.soak.bogus(rot, f"{leaf} {payload.decode()}")
            elif leaf == "status" and payload:
                doc = json.loads(payload)
                if doc.get("estimated"):
                    return
                for key, axis in (("bearing", "az"), ("elevation", "el"), ("raw_bearing", "az")):
                    value = doc.get(key)
                    raw = key == "raw_bearing"
                    if value is not None and not rot.was_reported(float(value), axis, raw):
                        self.soak.bogus(rot, f"status {key} {value}")
        except Exception as exc:  # noqa: BLE001  (a checker bug must not pass silently)
            self.soak.violation(f"monitor could not check {topic}: {exc!r}")

    def value(self, topic: str) -> bytes | None:
        with self.lock:
            got = self.latest.get(topic)
        return None if got is None else got[1]

    def since(self, topic: str) -> float:
        with self.lock:
            got = self.latest.get(topic)
        return -1e18 if got is None else got[0]

    def errors_after(self, rid: str, t: float) -> list[dict[str, Any]]:
        with self.lock:
            return [e for (ts, e) in self.errors[rid] if ts >= t]


class Soak:
    def __init__(self, minutes: float, seed: int, workdir: Path) -> None:
        self.duration_s = minutes * 60
        self.rng = random.Random(seed)
        self.seed = seed
        self.dir = workdir
        self.faults: Counter[str] = Counter()
        self.motion_faults: Counter[str] = Counter()
        self.cmds: Counter[str] = Counter()
        self.recoveries: list[tuple[str, float]] = []
        self.violations: list[str] = []
        self.bogus_list: list[str] = []
        self.misuse = 0  # frames a slewing SatEL logged as misuse
        self.late_retained = 0
        self.rss: list[tuple[float, int]] = []
        self.rots: dict[str, Rot] = {}
        self.broker_state = "up"
        self.broker_t = 0.0
        self.broker_next = 0.0
        self.broker_kind = ""
        self.broker_back = 0.0
        self.broker_why = ""  # why the retained state did not match yet after a broker fault
        self.exit_status: int | None = None
        self.exited_on_its_own = False
        self._vlock = threading.Lock()

    # -- bookkeeping ------------------------------------------------------------------------
    def violation(self, text: str) -> None:
        with self._vlock:
            self.violations.append(f"{time.monotonic() - self.t_start:7.1f}s {text}")
        print(f"VIOLATION: {text}", flush=True)

    def bogus(self, rot: Rot, what: str) -> None:
        with self._vlock:
            self.bogus_list.append(f"{rot.rid}: {what}")
        self.violation(f"bogus bearing from {rot.rid}: {what}")

    def log(self, text: str) -> None:
        if self.verbose:
            print(f"{time.monotonic() - self.t_start:7.1f}s {text}", flush=True)

    # -- set-up --------------------------------------------------------------------------------
    def setup(self) -> None:
        self.dir.mkdir(parents=True, exist_ok=True)
        self.broker = Mosquitto(self.dir / "broker", port=free_port()).start()
        rotators = []
        for rid, (model, emu_opts, bridge_opts) in ROTATORS.items():
            start = {"start_az_deg": 90.0} | ({"start_el_deg": 10.0} if model in AZEL else {})
            built = as_built(model)  # a Hy-Gain rotor's stop at south (emulators rule 3)
            emu = start_emulator(model, self.dir / f"tty-{rid}", **start, **built, **emu_opts)
            speed = float(emu_opts.get("speed_deg_s", emu_opts.get("az_speed_deg_s", 10.0)))
            self.rots[rid] = Rot(rid, model, emu, speed)
            rotators.append(
                {"id": rid, "model": model, "port": str(self.dir / f"tty-{rid}"), **bridge_opts}
            )
        config = {
            "state_file": str(self.dir / "state.json"),
            "log_level": "INFO",
            "mqtt": {"host": "127.0.0.1", "port": self.broker.port, "client_id": "soak-bridge"},
            "rotators": rotators,
        }
        self.bridge = BridgeProcess(self.dir, config, log_level="INFO").start()
        self.monitor = Monitor(self.broker.port, self)
        deadline = time.monotonic() + slow(60)
        while not all(self.healthy_view(r, READY) for r in self.rots.values()):
            if time.monotonic() > deadline:
                raise SystemExit(f"rotators not ready: {self.bridge.log()[-3000:]}")
            time.sleep(0.1)

    def healthy_view(self, rot: Rot, states: tuple[bytes, ...] = COMMANDABLE) -> bool:
        """Online, in a state the bridge takes a target in (``READY`` at the start)."""
        avail = self.monitor.value(f"rotor/{rot.rid}/availability")
        state = self.monitor.value(f"rotor/{rot.rid}/state")
        return avail == b"online" and state in states

    # -- the run -------------------------------------------------------------------------------
    def run(self, verbose: bool) -> int:
        self.verbose = verbose
        self.t_start = time.monotonic()
        self.setup()
        t0 = time.monotonic()
        for rot in self.rots.values():
            rot.next_fault = t0 + self.rng.uniform(5, 25)
            rot.next_cmd = t0 + self.rng.uniform(0.5, 3)
        self.broker_next = t0 + self.rng.uniform(15, 40)
        end_faults = t0 + max(20.0, self.duration_s - 20)  # then a final phase (< 1 min)
        next_audit = next_rss = t0
        try:
            while time.monotonic() < end_faults:
                now = time.monotonic()
                if not self.bridge.alive():
                    self.exited_on_its_own = True
                    self.violation(f"bridge exited on its own: {self.bridge.log()[-2000:]}")
                    break
                self.broker_step(now, allow_faults=True)
                for rot in self.rots.values():
                    self.rotator_step(rot, now, allow_faults=True)
                self.check_expectations(now)
                if now >= next_audit:
                    self.audit_frames()
                    next_audit = now + 0.5
                if now >= next_rss:
                    self.rss.append((now - t0, self.bridge.rss_kib()))
                    next_rss = now + 5
                time.sleep(0.05)
            if not self.exited_on_its_own:
                self.final_phase()
        finally:
            self.teardown()
        return self.report()

    # -- the broker ----------------------------------------------------------------------------
    def any_recovering(self) -> bool:
        return self.broker_state != "up" or any(r.recovering for r in self.rots.values())

    def broker_step(self, now: float, allow_faults: bool) -> None:
        if self.broker_state == "up":
            if allow_faults and now >= self.broker_next and not self.any_recovering():
                moving = any(r.emu.state().is_moving for r in self.rots.values())
                if self.rng.random() < 0.7:
                    self.broker_kind = "broker killed"
                    self.broker.kill()
                else:
                    self.broker_kind = "broker stopped"
                    self.broker.stop()
                self.faults[self.broker_kind] += 1
                self.motion_faults[self.broker_kind] += moving
                self.broker_state = "down"
                self.broker_t = now + self.rng.uniform(0.3, 6.0)
                self.log(f"{self.broker_kind} (moving: {moving})")
        elif self.broker_state == "down":
            if now >= self.broker_t:
                self.broker.start(10.0)  # same port, no persistence: every retained msg lost
                self.broker_state = "recovering"
                self.broker_t = time.monotonic()
        elif self.broker_state == "recovering":
            t_end = self.broker_t
            online_at = self.monitor.since("rotor/bridge/state")
            online = self.monitor.value("rotor/bridge/state") == b"online" and online_at > t_end
            if online:
                # rotators whose own line is still faulty or recovering are judged by their own
                # recovery (rotator_step, from when both the line and the broker are back): a
                # port the bridge reopens after its back-off says nothing about the broker
                ok, why = self.retained_ok(
                    [r for r in self.rots.values() if r.fault is None and r.recovering is None]
                )
                if not ok:
                    self.broker_why = why
                else:
                    took = time.monotonic() - t_end
                    self.recoveries.append((self.broker_kind, took))
                    late = time.monotonic() - online_at
                    if late > IDLE_POLL_S + RECOVERY_SLACK_S:
                        self.late_retained += 1
                        self.violation(
                            f"retained state late after {self.broker_kind}: matched {late:.1f} s "
                            f"after the bridge was back (until then: {self.broker_why or '-'})"
                        )
                    self.broker_why = ""
                    self.broker_state = "up"
                    self.broker_back = time.monotonic()
                    self.broker_next = time.monotonic() + self.rng.uniform(20, 50)
                    self.log(f"broker recovered in {took:.2f} s")
                    return
            if now - t_end > 60:
                self.violation(f"no recovery 60 s after {self.broker_kind}: {self.broker_why}")
                self.broker_state, self.broker_why = "up", ""

    def retained_ok(self, rots: list[Rot], estimate_ok: bool = True) -> tuple[bool, str]:
        """The broker's retained state (a fresh subscriber's view) against the ground truth. A
        SatEL's estimate during a slew passes unless ``estimate_ok`` is False."""
        try:
            snap = fast_retained(self.broker.port, "rotor/#")
        except Exception as exc:  # noqa: BLE001  (broker just restarted: try again)
            return False, repr(exc)
        if snap.get("rotor/bridge/state") != b"online":
            return False, "bridge/state"
        for rot in rots:
            r = f"rotor/{rot.rid}"
            if snap.get(f"{r}/availability") != b"online":
                return False, f"{rot.rid} availability {snap.get(f'{r}/availability')!r}"
            if rot.model == "dcu1":
                continue
            try:
                status = json.loads(snap.get(f"{r}/status", b"{}"))
            except ValueError:
                return False, f"{rot.rid} status unreadable"
            if status.get("bearing") is None:
                return False, f"{rot.rid} no bearing"
            if status.get("estimated"):
                if not estimate_ok:
                    return False, f"{rot.rid} position still estimated"
                continue
            truth = rot.emu.state()
            tol = 3.5 + (rot.speed * 0.8 if truth.is_moving else 0.0)
            wraps = True  # R/bearing is a true bearing (pointing.py), also on a SPID
            if not near_deg(float(status["bearing"]), truth.az_deg, tol, wraps):
                return False, f"{rot.rid} bearing {status['bearing']} vs {truth.az_deg:.1f}"
            if rot.model != "satel" and f"{r}/bearing" in snap:
                if not near_deg(float(snap[f"{r}/bearing"]), truth.az_deg, tol, wraps):
                    return False, f"{rot.rid} R/bearing {snap[f'{r}/bearing']!r}"
        return True, ""

    # -- a rotator -----------------------------------------------------------------------------
    def fault_kinds(self, rot: Rot) -> list[tuple[str, float]]:
        if rot.model == "dcu1":  # it never transmits: nothing to silence, cut short or garble
            return [("unplug", 3), ("power cycle", 1), ("garbage", 1)]
        kinds = [("unplug", 3), ("silent", 2), ("garbage", 3), ("cut short", 2), ("power cycle", 1)]
        if rot.model == "satel" and rot.emu.state().slewing:
            kinds.append(("report lost", 4))  # the SatEL's one after-move report, lost whole
        return kinds

    def recovery_limit_s(self, rot: Rot, kind: str) -> float:
        """How long after a fault the retained state may take to match the truth again: one
        poll, except after a lost SatEL report, which the bridge waits out for its slew's bound
        (twice the longest travel at the speeds it was told, plus 5 s), then stops and asks."""
        if kind == "report lost":
            return 2 * 360 / rot.speed + 5 + SATEL_STOP_REPORT_S + IDLE_POLL_S + RECOVERY_SLACK_S
        return IDLE_POLL_S + RECOVERY_SLACK_S + 0.5

    def rotator_step(self, rot: Rot, now: float, allow_faults: bool) -> None:
        if rot.fault is not None:
            self.fault_step(rot, now)
        elif rot.recovering is not None:
            kind, t_end = rot.recovering
            t_end = max(t_end, self.broker_back)  # from when both its line and the broker are back
            avail_at = self.monitor.since(f"rotor/{rot.rid}/availability")
            online = self.monitor.value(f"rotor/{rot.rid}/availability") == b"online"
            if online and self.broker_state == "up":
                ok, why = self.retained_ok([rot], estimate_ok=kind != "report lost")
                if not ok:
                    rot.why = why
                else:
                    took = now - t_end
                    self.recoveries.append((kind, took))
                    came_back = max(avail_at, t_end)
                    if now - came_back > self.recovery_limit_s(rot, kind):
                        self.late_retained += 1
                        self.violation(
                            f"{rot.rid}: retained state late after {kind}: matched "
                            f"{now - came_back:.1f} s after it was back (until then: "
                            f"{rot.why or '-'})"
                        )
                    rot.recovering, rot.why = None, ""
                    rot.next_fault = now + self.rng.uniform(8, 30)
                    self.log(f"{rot.rid} recovered from {kind} in {took:.2f} s")
            if rot.recovering is not None and now - t_end > 60 + self.recovery_limit_s(rot, kind):
                self.violation(f"{rot.rid}: no recovery 60 s after {kind}: {rot.why or '-'}")
                rot.recovering, rot.why = None, ""
        elif allow_faults and now >= rot.next_fault and self.broker_state == "up":
            self.start_fault(rot, now)
        elif self.broker_state == "up" and now >= rot.next_cmd:
            self.command(rot, now)

    def start_fault(self, rot: Rot, now: float) -> None:
        kinds, weights = zip(*self.fault_kinds(rot), strict=True)
        kind = self.rng.choices(kinds, weights)[0]
        moving = rot.emu.state().is_moving
        self.faults[kind] += 1
        self.motion_faults[kind] += moving
        fault = Fault(kind, now, now, moving)
        if kind == "unplug":
            fault.power_cycle = self.rng.random() < 0.5
            fault.t_end = now + self.rng.uniform(0.3, 5.0)
            rot.emu.unplug()
        elif kind == "silent":
            # short (the bridge rides it out) or clearly longer than silence_timeout_s (3 s:
            # offline, pending commands dropped); nothing in between, where either is right
            long = self.rng.random() < 0.5
            fault.t_end = now + (self.rng.uniform(4.5, 8.0) if long else self.rng.uniform(0.3, 2.0))
            rot.emu.set_silent(True)
        elif kind == "report lost":
            rot.emu.set_silent(True)  # the line is silent anyway while it slews
        # the link is down for the bridge: what was pending must never be sent afterwards (a
        # silent controller is declared offline silence_timeout_s = 3 s after its last reply;
        # not a slewing SatEL's: its line is silent while it slews, and a stop to it waits for
        # the report three times 2 s, then asks: a silence that ended by then is no link
        # down, and the target waiting is still the newest word, sent once it answers)
        if kind == "unplug":
            rot.stale_at.append(now)
        elif kind == "silent" and fault.t_end - now > 4 and not (rot.model == "satel" and moving):
            rot.stale_at.append(now + 4.0)
        # the rotor may be stopped or the command dropped: a move is not owed any more
        if kind in ("unplug", "power cycle") or (kind == "silent" and fault.t_end - now > 4):
            rot.last_interrupt_t = now
            if kind == "power cycle":
                rot.emu.power_cycle()
        else:
            fault.left = self.rng.randint(1, 4)
        rot.fault = fault
        self.log(f"{rot.rid}: {kind} (moving: {moving})")

    def fault_step(self, rot: Rot, now: float) -> None:
        f = rot.fault
        assert f is not None
        if f.kind == "report lost":
            gone = rot.emu.call(lambda d, now: not d.state(now).slewing and d._tx.pending() == 0)
            if gone:  # the slew ended and its report went out into nothing
                rot.emu.set_silent(False)
                self.end_fault(rot, now)
                if self.bridge_up() and self.rng.random() < 0.5:
                    self.target(rot, now)  # a new target while the bridge still waits
        elif f.kind in ("unplug", "silent"):
            offline = self.monitor.value(f"rotor/{rot.rid}/availability") == b"offline"
            if f.kind == "unplug" and offline and self.bridge_up() and self.rng.random() < 0.02:
                self.poison(rot, "while offline", now)  # a target meanwhile must be refused
            if now >= f.t_end:
                if f.kind == "unplug":
                    rot.emu.replug(power_cycle=f.power_cycle)
                else:
                    rot.emu.set_silent(False)
                self.end_fault(rot, now)
        elif f.kind in ("garbage", "cut short"):
            if f.left == 0:
                self.end_fault(rot, now)
            elif now >= f.next_t and self.line_quiet(rot):
                model = rot.model if rot.model != "dcu1" else "rotorez"
                spid_busy = rot.model in SPID and rot.emu.state().is_moving
                if f.kind == "cut short" and not spid_busy:
                    rot.emu.inject(cut_short(self.rng, model, rot.emu))
                else:
                    noise = line_noise(self.rng, model)
                    if rot.model == "satel" and self.rng.random() < 0.5:
                        noise = noise.rstrip(b"\r\n")  # noise without a line end, too
                    rot.emu.inject(noise)
                f.left -= 1
                f.next_t = now + self.rng.uniform(0.1, 1.0)
        else:
            self.end_fault(rot, now)

    def line_quiet(self, rot: Rot) -> bool:
        """Between replies: the controller's transmitter is idle (garbage goes between replies)."""
        return rot.emu.call(lambda d, now: d._tx.pending() == 0)

    def end_fault(self, rot: Rot, now: float) -> None:
        assert rot.fault is not None
        rot.recovering = (rot.fault.kind, now)
        rot.fault = None

    # -- commands ------------------------------------------------------------------------------
    def bridge_up(self) -> bool:
        return (
            self.broker_state == "up"
            and self.monitor.client.is_connected()
            and self.monitor.value("rotor/bridge/state") == b"online"
        )

    def command(self, rot: Rot, now: float) -> None:
        if not self.bridge_up() or not self.healthy_view(rot) or self.any_recovering():
            return
        e = rot.expectation
        idle = e is None or e.outcome is not None
        # mostly wait for the move, sometimes re-target; never a stalled one: a stall is no
        # excuse for an open command, judged by its deadline (lost, unless a serial fault
        # interrupted it), never replaced unjudged; once it is judged, the next one goes
        stalled = self.monitor.value(f"rotor/{rot.rid}/state") == b"stalled"
        if not idle and (stalled or self.rng.random() > 0.15):
            rot.next_cmd = now + 2.0
            return
        roll = self.rng.random()
        if idle and roll < 0.05:
            self.poison(rot, "retained", now)
        elif idle and roll < 0.10:
            self.poison(rot, "locked", now)
        elif roll < 0.15:
            self.poison(rot, self.rng.choice(["out of limits", "bad payload"]), now)
        else:
            self.target(rot, now)
        rot.next_cmd = time.monotonic() + self.rng.uniform(1.0, 6.0)

    def pick(self, rot: Rot) -> tuple[float, float | None]:
        truth = rot.emu.state()
        while True:
            az = 5.0 * self.rng.randint(0, 71)
            if abs(az - truth.az_deg) >= 15:
                break
        el = 5.0 * self.rng.randint(0, 17) if rot.model in AZEL else None
        if rot.model == "satel":  # (is_poison: never a refused command's elevation)
            el = 20.0 * self.rng.randint(0, 4)
        return az, el

    def payload(self, rot: Rot, az: float, el: float | None) -> str:
        if el is None:
            return f"{az:g}" if self.rng.random() < 0.5 else json.dumps({"azimuth": az})
        return (
            f"{az:g} {el:g}"
            if self.rng.random() < 0.5
            else json.dumps({"azimuth": az, "elevation": el})
        )

    def target(self, rot: Rot, now: float) -> None:
        az, el = self.pick(rot)
        text = self.payload(rot, az, el)
        if rot.expectation is not None and rot.expectation.outcome is None:
            rot.expectation.outcome = "superseded"
            self.cmds["superseded"] += 1
        t = time.monotonic()
        self.monitor.publish(f"rotor/{rot.rid}/target", text)
        self.cmds["sent"] += 1
        az, el = reaches(rot.model, az, el)
        rot.accepted.append((t, az, el))
        dist = abs(az - rot.emu.state().az_deg) + (0 if el is None else 0)
        travel = dist / rot.speed
        if rot.model == "dcu1":
            travel = max(travel, 360 / 6.0) + 10  # the bridge assumes worst-case travel first
        rot.expectation = Expectation(az, el, t, t + travel + 30.0, text)

    def poison(self, rot: Rot, kind: str, now: float) -> None:
        """A command the bridge must refuse; its azimuth is a poison value (never allowed to move
        anything)."""
        az = 5.0 * self.rng.randint(0, 70) + 2.0
        el = (30.0 if rot.model == "satel" else 12.0) if rot.model in AZEL else None
        text = f"{az:g}" if el is None else f"{az:g} {el:g}"
        topic = f"rotor/{rot.rid}/target"
        t = time.monotonic()
        if kind == "retained":
            self.monitor.publish(topic, text, retain=True)
        elif kind == "locked":
            self.monitor.publish(f"rotor/{rot.rid}/lock", "ON")
            if not self.wait(lambda: self.monitor.value(f"rotor/{rot.rid}/lock/state") == b"ON"):
                self.violation(f"{rot.rid}: lock ON not confirmed")
            self.monitor.publish(topic, text)
        elif kind == "out of limits":
            text = "400" if el is None else "90 300"
            self.monitor.publish(topic, text)
        elif kind == "bad payload":
            text = self.rng.choice(["north", "1e999", '{"azimuth": "x"}', "\xff\xfe", "12 34 56"])
            self.monitor.publish(topic, text.encode("latin-1"))
        else:  # while offline
            self.monitor.publish(topic, text)
        self.cmds[f"refusable: {kind}"] += 1
        refused = self.wait(lambda: bool(self.monitor.errors_after(rot.rid, t)), 5.0)
        if refused:
            self.cmds["refused as they must be"] += 1
        elif kind != "while offline" or self.monitor.value(f"rotor/{rot.rid}/availability") == (
            b"offline"
        ):
            self.violation(f"{rot.rid}: {kind} command {text!r} not refused")
        if kind == "retained":
            self.monitor.publish(topic, b"", retain=True)  # cleared, as the error says
        if kind == "locked":
            self.monitor.publish(f"rotor/{rot.rid}/lock", "OFF")
            if not self.wait(lambda: self.monitor.value(f"rotor/{rot.rid}/lock/state") == b"OFF"):
                self.violation(f"{rot.rid}: lock OFF not confirmed")

    def wait(self, predicate: Any, timeout_s: float = 5.0) -> bool:
        deadline = time.monotonic() + slow(timeout_s)
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(0.01)
        return bool(predicate())

    # -- invariants ----------------------------------------------------------------------------
    def arrived(self, rot: Rot, e: Expectation) -> bool:
        s = rot.emu.state()
        if s.is_moving or s.in_brake_delay:
            return False
        tol = 3.5 if rot.model in ROTOREZ_FAMILY else 1.0
        if not near_deg(s.az_deg, e.az, tol):  # a direction: a SPID's raw -170 is true 190
            return False
        return e.el is None or abs(s.el_deg - e.el) <= tol

    def check_expectations(self, now: float) -> None:
        for rot in self.rots.values():
            e = rot.expectation
            if e is None or e.outcome is not None:
                continue
            if self.arrived(rot, e):
                e.outcome, e.t_done = "arrived", now
                self.cmds["arrived"] += 1
            elif rot.last_interrupt_t > e.t0:
                e.outcome = "interrupted by a serial fault"
                self.cmds["interrupted by a serial fault"] += 1
            elif self.restart_said(rot, e):
                # a power cycle just before it was asked, found by the exchange after: the
                # bridge drops what waits and says so, naming it (a SatEL's clock went back)
                e.outcome = "interrupted by a serial fault"
                self.cmds["interrupted by a serial fault"] += 1
            elif now > e.deadline:
                e.outcome = "lost"
                self.cmds["lost"] += 1
                s = rot.emu.state()
                errors = self.monitor.errors_after(rot.rid, e.t0)
                self.violation(
                    f"{rot.rid}: command {e.payload!r} lost: rotor at {s.az_deg:.1f}"
                    f"{'' if s.el_deg is None else f'/{s.el_deg:.1f}'}; errors {errors[-3:]}"
                )

    def restart_said(self, rot: Rot, e: Expectation) -> bool:
        """A controller restart the bridge reported after ``e`` was asked, naming its target
        (as the error's command, or as the turn it says was not resumed: a power-on byte in a
        garbage fault's noise is one, session/controller.py rule 12)."""
        for error in self.monitor.errors_after(rot.rid, e.t0):
            command, message = str(error.get("command", "")), str(error.get("message", ""))
            if "restarted" in message and (
                command.startswith("target") or f"its turn to {e.az:g}°" in message
            ):
                return True
        return False

    def frame_target(self, rot: Rot, data: bytes) -> tuple[float, float | None] | None:
        try:
            if rot.model in ROTOREZ_FAMILY:
                if not data.startswith(b"AP1"):
                    return None
                return float(int(data[3:6])), None
            if rot.model == "satel":
                az, el = data[1:].strip().split(b" ")
                return float(int(az)), float(int(el))
            ppd = rot.emu.state().resolution_ppd
            return int(data[1:5]) / ppd - 360.0, int(data[6:10]) / ppd - 360.0
        except ValueError:
            return None

    def audit_frames(self) -> None:
        """Every target the controllers obeyed was accepted, fresh, and not a refused one; and
        a slewing SatEL was sent nothing but a stop (its manual: input while slewing can wedge
        it; the emulator logs every such byte)."""
        for rot in self.rots.values():
            log = rot.emu.log()
            new, rot.frames_seen = log[rot.frames_seen :], len(log)
            for frame in new:
                if frame.outcome == "misuse: input while slewing":
                    self.misuse += 1
                    self.violation(f"{rot.rid}: {frame.data!r} sent while it was slewing")
                    continue
                if rot.model in SPID:
                    motion = frame.outcome in ("set", "set: clamped")
                elif rot.model == "satel":
                    motion = frame.outcome == "slew"
                else:
                    motion = frame.outcome in BEARING_OUTCOMES and frame.data.startswith(b"AP1")
                if not motion:
                    continue
                got = self.frame_target(rot, frame.data)
                if got is None:
                    self.violation(f"{rot.rid}: unreadable target frame {frame.data!r}")
                    continue
                az, el = got
                if is_poison(rot.model, az, el):
                    self.violation(f"{rot.rid}: motion from a refused command {frame.data!r}")
                    continue
                since = max((t for t in rot.stale_at if t < frame.time_s), default=-1e9)
                fresh = [
                    (t, a, e)
                    for (t, a, e) in rot.accepted
                    if since < t <= frame.time_s + 0.05
                    # as a direction on every model: a SPID reaches true 310 at raw -50 when
                    # that side needs less travel (pointing.py, the overlap)
                    and near_deg(a, az, 1.0)
                    and (el is None or e is None or abs(e - el) <= 1.0)
                ]
                if not fresh:
                    self.violation(
                        f"{rot.rid}: motion from a stale or unknown command {frame.data!r} "
                        f"(link last down at {since - self.t_start:.1f}s)"
                    )

    # -- the end -------------------------------------------------------------------------------
    def final_phase(self) -> None:
        """No new faults: let everything recover, then one last target each, all must arrive."""
        deadline = time.monotonic() + slow(90)
        while True:
            now = time.monotonic()
            self.broker_step(now, allow_faults=False)
            for rot in self.rots.values():
                if rot.fault is not None or rot.recovering is not None:
                    self.rotator_step(rot, now, allow_faults=False)
            self.check_expectations(now)
            self.audit_frames()
            busy = [
                r
                for r in self.rots.values()
                if r.fault or r.recovering or (r.expectation and r.expectation.outcome is None)
            ]
            if not busy and self.broker_state == "up":
                break
            # a command still open is judged by its own deadline (lost or not), never replaced
            # unjudged by the last target below
            open_until = max((r.expectation.deadline for r in busy if r.expectation), default=0.0)
            if now > max(deadline, open_until + 1.0):
                self.violation(
                    f"still busy {now - deadline + 90:.0f} s after the last fault: "
                    f"{', '.join(r.rid for r in busy) or 'the broker'}"
                )
                break
            time.sleep(0.05)
        for rot in self.rots.values():
            if self.bridge_up() and self.healthy_view(rot):
                self.target(rot, time.monotonic())
            else:
                self.violation(f"{rot.rid}: not healthy at the end")
        deadline = time.monotonic() + slow(90)
        while time.monotonic() < deadline:
            self.check_expectations(time.monotonic())
            if all(r.expectation and r.expectation.outcome for r in self.rots.values()):
                break
            time.sleep(0.1)
        never = time.monotonic() + 1e6  # not a deadline: a time past every one
        self.check_expectations(never)  # anything still open now is lost
        self.audit_frames()
        # the wait above ends the moment the last rotor stands at its target; the bridge sees
        # that at its next reading, so the retained state may take one poll, as after a
        # recovery (a Rot2Prog's readings at 600 baud come ~0.4 s apart and ~0.4 s old: 6 deg
        # behind a rotor turning 10 deg/s is no error, but one that stays behind is)
        settle_by = time.monotonic() + IDLE_POLL_S + RECOVERY_SLACK_S
        ok, why = self.retained_ok(list(self.rots.values()))
        while not ok and time.monotonic() < settle_by:
            time.sleep(0.1)
            ok, why = self.retained_ok(list(self.rots.values()))
        if not ok:
            self.violation(f"retained state wrong at the end: {why}")
        self.rss.append((time.monotonic() - self.t_start, self.bridge.rss_kib()))

    def teardown(self) -> None:
        try:
            if self.broker.proc is None:
                self.broker.start(10.0)
            if self.bridge.alive():
                self.exit_status = self.bridge.terminate(15)
                snap = fast_retained(self.broker.port, "rotor/#")
                if snap.get("rotor/bridge/state") != b"offline":
                    self.violation("bridge/state not offline after SIGTERM")
            elif self.bridge.proc is not None:
                self.exit_status = self.bridge.proc.returncode
        finally:
            self.bridge.kill()
            self.monitor.close()
            for rot in self.rots.values():
                rot.emu.close()
            self.broker.stop()

    # -- the table -----------------------------------------------------------------------------
    def report(self) -> int:
        minutes = (time.monotonic() - self.t_start) / 60
        rss_start = self.rss[min(2, len(self.rss) - 1)][1] if self.rss else 0
        rss_end = self.rss[-1][1] if self.rss else 0
        rss_max = max((r for _, r in self.rss), default=0)
        if self.rss and rss_end - rss_start > 20 * 1024:
            self.violation(f"memory grew {rss_start} -> {rss_end} KiB")
        rec = [t for _, t in self.recoveries]
        worst = max(self.recoveries, key=lambda kt: kt[1], default=("-", 0.0))
        lines = [
            f"rotor-bridge soak: {minutes:.1f} min, seed {self.seed}, "
            f"{len(self.rots)} rotators ({', '.join(r.model for r in self.rots.values())})",
            "",
            "| faults injected (kind) | count | of which during motion |",
            "|---|---:|---:|",
        ]
        for kind in sorted(self.faults):
            lines.append(f"| {kind} | {self.faults[kind]} | {self.motion_faults[kind]} |")
        lines.append(f"| **total** | {sum(self.faults.values())} | "
                     f"{sum(self.motion_faults.values())} |")  # fmt: skip
        by_kind: dict[str, list[float]] = defaultdict(list)
        for kind, took in self.recoveries:
            by_kind[kind].append(took)
        lines += ["", "| recovery after | count | median s | worst s |", "|---|---:|---:|---:|"]
        for kind in sorted(by_kind):
            ts = by_kind[kind]
            lines.append(f"| {kind} | {len(ts)} | {statistics.median(ts):.2f} | {max(ts):.2f} |")
        lost = self.cmds["lost"]
        lines += [
            "",
            "| invariant / measure | value |",
            "|---|---:|",
            f"| recoveries | {len(rec)} |",
            f"| worst recovery time | {worst[1]:.2f} s ({worst[0]}) |",
            f"| retained state not matching within one poll of recovery | {self.late_retained} |",
            f"| targets sent (accepted while the link was up) | {self.cmds['sent']} |",
            f"| ... arrived | {self.cmds['arrived']} |",
            f"| ... replaced by a newer target before arriving | {self.cmds['superseded']} |",
            f"| ... interrupted by a serial fault on that rotator | "
            f"{self.cmds['interrupted by a serial fault']} |",
            f"| **commands lost** | **{lost}** |",
            f"| commands that must be refused (retained, locked, offline, invalid) | "
            f"{sum(v for k, v in self.cmds.items() if k.startswith('refusable'))} |",
            f"| ... refused | {self.cmds['refused as they must be']} |",
            f"| **bogus bearings** | **{len(self.bogus_list)}** |",
            f"| **input to a slewing SatEL other than a stop** | **{self.misuse}** |",
            f"| MQTT messages checked | {self.monitor.count} |",
            f"| bridge RSS start / end / max | {rss_start / 1024:.1f} / {rss_end / 1024:.1f} / "
            f"{rss_max / 1024:.1f} MiB |",
            f"| bridge exited on its own | {'YES' if self.exited_on_its_own else 'no'} |",
            f"| bridge exit status (SIGTERM at the end) | {self.exit_status} |",
            f"| invariant violations | {len(self.violations)} |",
        ]
        if self.exit_status not in (0, None) and not self.exited_on_its_own:
            self.violation(f"exit status {self.exit_status} after SIGTERM")
        result = "PASS" if not self.violations else "FAIL"
        lines += ["", f"result: {result}"]
        lines += [f"  {v}" for v in self.violations[:30]]
        table = "\n".join(lines)
        print(table, flush=True)
        (self.dir / "soak-report.md").write_text(table + "\n")
        return 0 if result == "PASS" else 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tests.soak", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--minutes", type=float, default=10.0, help="length of the run (10)")
    parser.add_argument("--seed", type=int, default=None, help="random seed (printed)")
    parser.add_argument("--workdir", type=Path, default=None, help="keep logs here")
    parser.add_argument("-v", "--verbose", action="store_true", help="print every fault")
    args = parser.parse_args(argv)
    seed = args.seed if args.seed is not None else random.randrange(1 << 30)
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="rotor-bridge-soak-"))
    print(f"soak: {args.minutes} min, seed {seed}, logs in {workdir}", flush=True)
    return Soak(args.minutes, seed, workdir).run(args.verbose)


if __name__ == "__main__":
    sys.exit(main())
