"""What one poll exchange costs the serial-lines thread, in virtual time: deterministic, in
seconds, for iterating on the work of a reading (exchange_cpu measures the real thing).

    python -m benchmarks.session_cost [--exchanges N] [--profile] [--held]

One Rotor-EZ turned from its front panel (no command: the bridge polls it at its moving rate and
every reply moves the bearing), its replies byte by byte as the emulator paces them, driven in
virtual time as the worker drives a session (tests/engine/virtual.py). Timed with
``time.perf_counter``: every call into the session (``tick``, ``bytes_received``) and what the
worker does with the actions it hands back for a status: the MQTT service's ``publish_status``
into a publisher that keeps the retained payloads (the dedupe a real client does, no paho).
The emulator and the line are not timed. Printed: microseconds per exchange (an ``AI1;``
written), the session's and the publishing's shares, and the session calls per exchange;
``--profile``: cProfile of the same, the 25 heaviest by own time. ``--held``: the replies handed
over as the bridge's worker hands them (runtime/worker.py rule 2: left in the port until the
session's ``hold_reads_until``, then read in one go; three session calls an exchange, where
the default's byte by byte makes six).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time
from typing import Any

from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from bridge.session.actions import Publish
from tests.engine.virtual import VirtualRotator
from tests.mqtt.test_service import RecordingPublisher, RecordingRotator

POLL = b"AI1;"


class _Timed(VirtualRotator):
    """The session's calls and the status's publishing, timed (the rest of the bench is not)."""

    def __init__(self, svc: MqttService, **kw: Any) -> None:
        self.svc = svc
        self.session_s = 0.0
        self.publish_s = 0.0
        self.calls = 0
        super().__init__("rotorez", **kw)
        session = self.session
        for name in ("tick", "bytes_received"):
            setattr(session, name, self._timed(getattr(session, name)))

    def _timed(self, call: Any) -> Any:
        def timed(*args: Any) -> Any:
            t0 = time.perf_counter()
            out = call(*args)
            self.session_s += time.perf_counter() - t0
            self.calls += 1
            return out

        return timed

    def _do(self, actions: Any) -> None:
        actions = list(actions)
        t0 = time.perf_counter()
        for action in actions:
            if isinstance(action, Publish):
                self.svc.publish_status("v", action.status)
        self.publish_s += time.perf_counter() - t0
        super()._do(actions)


class _Held(_Timed):
    """The replies held in the port as the worker holds them, then read whole."""

    def __init__(self, svc: MqttService, **kw: Any) -> None:
        self._port = b""
        super().__init__(svc, **kw)

    def _step(self, until: float) -> None:
        s = self.session
        times = [until, s.next_wakeup(), *self._wire_times()]
        hold = s.hold_reads_until()
        if self._port or hold > self.now:
            times.append(hold)
        t = self.now = max(self.now, min(times))
        arrived = self._tx.due(t)
        if arrived:
            self.device.receive(arrived, t)
        self._port += self.device.due_output(t)
        acted = False
        if self._port and t >= s.hold_reads_until():
            data, self._port = self._port, b""
            actions = s.bytes_received(data, t)
            if actions:
                acted = True
                self._do(actions)
        if not acted and t >= s.next_wakeup():
            self._do(s.tick(t))


def run(exchanges: int, held: bool = False) -> dict[str, float]:
    pub = RecordingPublisher()
    svc = MqttService(Topics("rotor", {"v": "rotor"}), pub, wall=lambda: 1_750_000_000.0)
    svc.attach(RecordingRotator("v", "rotorez"))
    v = (_Held if held else _Timed)(svc, emulator={"speed_deg_s": 4.0})
    v.run_for(3.0)  # online, idle, options read
    v.session_s = v.publish_s = 0.0
    v.calls = 0
    start = len(v.writes)
    sent0 = len(pub.sent)
    az = 350.0
    while sum(1 for w in v.writes[start:] if w.data == POLL) < exchanges:
        v.manual_rotate(az)
        v.run_until(lambda h: not h.truth().is_moving, 200.0, "the turn ends")
        az = 10.0 if az > 180 else 350.0
    n = sum(1 for w in v.writes[start:] if w.data == POLL)
    return {
        "exchanges": n,
        "us_per_exchange": (v.session_s + v.publish_s) / n * 1e6,
        "session_us": v.session_s / n * 1e6,
        "publish_us": v.publish_s / n * 1e6,
        "calls_per_exchange": v.calls / n,
        "publishes_per_exchange": (len(pub.sent) - sent0) / n,
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--exchanges", type=int, default=3000)
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--held", action="store_true", help="replies read whole, as the worker does")
    args = ap.parse_args()
    if args.profile:
        prof = cProfile.Profile()
        prof.enable()
        run(args.exchanges, args.held)
        prof.disable()
        pstats.Stats(prof).sort_stats("tottime").print_stats(25)
        return
    best: dict[str, float] | None = None
    for _ in range(5):
        r = run(args.exchanges, args.held)
        if best is None or r["us_per_exchange"] < best["us_per_exchange"]:
            best = r
    assert best is not None
    print(
        f"{best['us_per_exchange']:.1f} us/exchange (session {best['session_us']:.1f}, "
        f"publish {best['publish_us']:.1f}); {best['calls_per_exchange']:.2f} session calls, "
        f"{best['publishes_per_exchange']:.2f} retained publishes per exchange; "
        f"{best['exchanges']:.0f} exchanges, best of 5"
    )


if __name__ == "__main__":
    main()
