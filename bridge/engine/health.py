"""Rotor health, the session's part that watches how the rotor really turns: it cuts the motion
machine's readings into moves and measures each (speed each way over the steady part, start
delay, coast after a stop, arrival error, stalls and where, degrees turned, motor-on time);
health_judge.py adds them up and judges them. A part (docs/architecture.md, "parts decide and
return"): it owns its state, is handed the motion (read-only) and the time at every step, and
returns a new report when a move has ended; the session puts it in the status. Nothing new goes
on the line: it reads only what the polls bring.

Rules:
1. A move starts when the motion machine says ``moving`` (a command sent, or a hand on the
   front panel) and ends when it says anything else; a new target while it turns (a controller
   that takes one, SPID) ends the move and starts another. A move that ends offline or
   unknown is forgotten: the readings stopped, nothing can be said of it.
2. The speed of a move is measured over its steady part only: the readings between 20 % and
   80 % of the way it turned (STEADY), so neither the start (the start delay, a motor coming
   up to speed) nor the end (braking, coasting, a slow approach) counts; a move too short for
   MIN_SPAN_S and MIN_SPAN_DEG of steady readings gives no speed. Its direction is the way it
   turned: clockwise (raw azimuth growing) or counter-clockwise; up or down in elevation.
3. The start delay is from the command to the first reading that differs from where the rotor
   stood, for a move from rest whose turning the polls saw; a move without a command (the
   front panel), a new target taken while turning and a controller silent while it turns
   (SatEL) give none. The coast is what the rotor turned after the bridge's stop: from
   where it was when the stop went out (the last reading carried on at its speed) to where it
   came to rest.
4. A stall is the motion machine's; it is counted at the raw azimuth where it happened.
5. A report is made only when a move ends (and at the start): statuses between moves carry
   the same report object, so nothing is published per poll. A controller that reports no
   position (DCU-1) has a report that says so and never another.
6. Cheap at every step: a motion already seen costs one comparison, a new one a few more and
   a reading appended while the rotor turns (at most MAX_READINGS a move: a rotor "turning"
   for hours, a noisy potentiometer, does not grow without end; its first hour is measured).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from bridge.engine import motion as mo
from bridge.engine.config import WorkerConfig
from bridge.engine.health_judge import Judge, Move
from bridge.model import MotionState, RotatorHealth

STEADY = (0.2, 0.8)  # rule 2
MIN_SPAN_S = 1.0
MIN_SPAN_DEG = 5.0
MAX_READINGS = 20_000  # rule 6: over an hour of readings at 0.2 s
_GONE = (MotionState.OFFLINE, MotionState.UNKNOWN)


@dataclass
class _Move:
    """A move under way: its command, its stop, its readings (time, raw az, el)."""

    target_t: float | None
    from_az: float
    from_el: float | None
    readings: list[tuple[float, float, float | None]] = field(default_factory=list)
    target_az: float | None = None
    target_el: float | None = None
    first_change_t: float | None = None
    stop_t: float | None = None
    from_rest: bool = True  # not a new target taken while turning (rule 3: no start delay)


class Health:
    def __init__(self, cfg: WorkerConfig, memory: Mapping[str, object] | None = None) -> None:
        self._measured = cfg.spec.can_report_position
        self._wraps = cfg.spec.az_wraps
        self._has_el = cfg.spec.has_elevation
        self._judge = Judge(cfg.health, self._has_el, memory)
        self.report = self._judge.report() if self._measured else RotatorHealth(measured=False)
        self._move: _Move | None = None
        self._changed_t: float | None = None
        self._stop_t: float | None = None
        self._seen: mo.Motion | None = None  # the motion last looked at

    def reset(self) -> RotatorHealth | None:
        """A new baseline (health_judge.py rule 5); the new report."""
        if not self._measured:
            return None
        self._judge.reset()
        self.report = self._judge.report()
        return self.report

    def step(self, m: mo.Motion, now: float) -> RotatorHealth | None:
        """Run by the session after every input; a new report when a move has ended."""
        if m is self._seen or not self._measured:
            return None  # rule 6: the motion is a new object whenever anything in it changed
        self._seen = m
        move = self._move
        if m.changed_t is not None and m.changed_t != self._changed_t:
            self._changed_t = m.changed_t
            if move is not None and m.position_deg is not None:
                self._reading(move, m, m.changed_t, m.position_deg)
        if m.stop_sent_t is not None and m.stop_sent_t != self._stop_t:
            self._stop_t = m.stop_sent_t
            if move is not None and move.stop_t is None:
                move.stop_t = m.stop_sent_t
        if m.state is MotionState.MOVING:
            retarget = move is not None and m.target_t is not None and m.target_t != move.target_t
            if move is not None and retarget and move.target_t is not None:
                self._move = None
                ended = self._ended(move, m)  # rule 1: a new target while turning
                self._start(m, from_rest=False)
                return ended
            if move is None:
                self._start(m)
            elif m.target_deg is not None:
                move.target_az, move.target_el = m.target_deg, m.el_target_deg
            return None
        if move is None:
            return None
        self._move = None
        if m.state in _GONE:
            return None  # rule 1
        return self._ended(move, m)

    def _start(self, m: mo.Motion, *, from_rest: bool = True) -> None:
        if m.position_deg is None:
            return
        move = _Move(m.target_t, m.position_deg, m.el_position_deg, from_rest=from_rest)
        move.target_az, move.target_el = m.target_deg, m.el_target_deg
        move.readings.append((m.target_t or m.changed_t or 0.0, m.position_deg, m.el_position_deg))
        if m.target_t is None:  # the front panel: it has moved already (rule 3: no delay)
            move.first_change_t = m.changed_t
        self._move = move

    def _reading(self, move: _Move, m: mo.Motion, t: float, az: float) -> None:
        if len(move.readings) < MAX_READINGS:  # rule 6
            move.readings.append((t, az, m.el_position_deg))
        if move.first_change_t is None and (
            az != move.from_az or m.el_position_deg != move.from_el
        ):
            move.first_change_t = t

    def _ended(self, move: _Move, m: mo.Motion) -> RotatorHealth | None:
        values: dict[str, float] = {}
        travel = [0.0, 0.0]
        az = self._unwrapped([r[1] for r in move.readings])
        axes: list[tuple[str, list[float]]] = [("az", az)]
        if self._has_el and all(r[2] is not None for r in move.readings):
            axes.append(("el", [r[2] for r in move.readings if r[2] is not None]))
        times = [r[0] for r in move.readings]
        for i, (axis, path) in enumerate(axes):
            travel[i] = sum(abs(b - a) for a, b in zip(path, path[1:], strict=False))
            self._speed(axis, times, path, move.stop_t, values)
            if move.stop_t is not None:
                coast = _coast(times, path, move.stop_t)
                if coast is not None:
                    values[f"{axis}_coast"] = coast
        stalled = m.state is MotionState.STALLED
        turned = move.first_change_t is not None
        if move.target_t is not None and move.from_rest and move.first_change_t is not None:
            seen_turning = sum(1 for r in move.readings if r[0] > move.first_change_t) >= 2
            if seen_turning:  # not a silent slew's report at its end (SatEL)
                values["delay"] = max(0.0, move.first_change_t - move.target_t)
        errors: list[float | None] = [None, None]
        if not stalled and move.stop_t is None and m.position_deg is not None:
            if move.target_az is not None:
                errors[0] = mo.angle_error(m.position_deg, move.target_az, self._wraps)
            if move.target_el is not None and m.el_position_deg is not None:
                errors[1] = abs(m.el_position_deg - move.target_el)
        if not turned and not stalled:
            return None  # nothing turned (already there): no move to speak of
        start_t = move.target_t if move.target_t is not None else times[0]
        done = Move(
            values=values,
            travel_deg=(travel[0], travel[1]),
            arrival_error_deg=(errors[0], errors[1]),
            motor_on_s=max(0.0, times[-1] - start_t) if turned else 0.0,
            stalled_at_deg=m.position_deg if stalled else None,
        )
        self._judge.add(done)
        self.report = self._judge.report()
        return self.report

    def _unwrapped(self, az: list[float]) -> list[float]:
        """Raw azimuths as a continuous path (a scale that wraps at 360: 359 -> 1 is +2)."""
        if not self._wraps:
            return az
        out = [az[0]]
        for before, a in zip(az, az[1:], strict=False):
            out.append(out[-1] + (a - before + 180.0) % 360.0 - 180.0)
        return out

    def _speed(
        self,
        axis: str,
        times: list[float],
        path: list[float],
        stop_t: float | None,
        values: dict[str, float],
    ) -> None:
        """Rule 2: over the steady part, up to the stop (what follows it is coasting)."""
        n = len(path)
        if stop_t is not None:
            n = sum(1 for t in times if t <= stop_t)
        if n < 3:
            return
        total = path[n - 1] - path[0]
        if abs(total) < MIN_SPAN_DEG:
            return
        lo, hi = path[0] + STEADY[0] * total, path[0] + STEADY[1] * total
        inside = [
            i for i in range(n) if (lo <= path[i] <= hi if total > 0 else hi <= path[i] <= lo)
        ]
        if len(inside) < 2:
            return
        a, b = inside[0], inside[-1]
        span_s, span_deg = times[b] - times[a], abs(path[b] - path[a])
        if span_s >= MIN_SPAN_S and span_deg >= MIN_SPAN_DEG:
            values[f"{axis}_{'up' if total > 0 else 'down'}"] = span_deg / span_s


def _coast(times: list[float], path: list[float], stop_t: float) -> float | None:
    """Rule 3: from where the rotor was at the stop (the last reading before it, carried on
    at the speed of the two last) to where it came to rest, the way it was turning."""
    before = [i for i, t in enumerate(times) if t <= stop_t]
    if len(before) < 2:
        return None
    i, j = before[-2], before[-1]
    dt = times[j] - times[i]
    speed = (path[j] - path[i]) / dt if dt > 0 else 0.0
    at_stop = path[j] + speed * (stop_t - times[j])
    way = 1.0 if speed >= 0 else -1.0
    return max(0.0, (path[-1] - at_stop) * way)
