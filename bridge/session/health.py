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
   unknown is forgotten: the readings stopped, nothing can be said of it. The first reading
   back after a replug mid-turn, taken for a turn (motion.py rule 4), starts none until a
   reading shows the rotor move (a review: one that had come to rest meanwhile was counted
   a move, its pot's jitter for its turning).
2. The speed of a move is measured over its steady part only: the readings between 20 % and
   80 % of the way it turned (STEADY), so neither the start (the start delay, a motor coming
   up to speed) nor the end (braking, coasting, a slow approach) counts; a move too short for
   MIN_SPAN_S and MIN_SPAN_DEG of steady readings gives no speed. Its direction is the way it
   turned: clockwise (raw azimuth growing) or counter-clockwise; up or down in elevation.
3. The start delay is from the command to when the rotor left where it stood: the first
   reading beyond the motion machine's noise band from there (a still potentiometer's jitter is
   no start), set back by the way it had gone at the move's steady speed; a move too short for
   one (a tracking step, a nudge) is set back at the speed that way the recent moves or the
   baseline give, and gives none while no speed is known (a review: its first reading beyond
   the band taken as its start, a Rotor-EZ's 0.1 s start read 0.8 s, and a few small steps
   warned of a start delay grown seven times over); for a move from rest
   whose turning the polls saw (and that left the band); a move without a command (the
   front panel), a new target taken while turning and a controller silent while it turns
   (SatEL) give none. The coast is what the rotor turned after the bridge's stop: from
   where it was when the stop went out (the last reading carried on at its speed) to where it
   came to rest; a stop sent again (stops.py rule 2) counts from the first the rotor obeyed:
   not one after which it went on, over the second half of the time until the next went out
   ``stop_resend_s`` or more after it (as stops.py rule 2 sends a lost one again), at
   HEARD_SHARE or more of the speed it came at over SPEED_SPAN_S (it did not slow: a stop
   the line lost; a review found the rotor's full speed for 2 s counted as its coast, 13
   degrees where it coasts one, and a few such stops warned that the brake no longer holds).
   A rotor still that fast a second after a stop it heard has its coast counted from the
   next. A stop followed only by stops sent sooner (the operator's STOP again while the rotor
   coasts) is taken as obeyed: a few readings so soon after it tell no coast from a drive (a
   review: whole degrees read a slipping brake's 9 degree coast as a drive, counted from the
   second STOP, 1.5 to 7 degrees). An axis not turning when that stop went out (an
   elevation-only move's azimuth, an axis that had arrived) has no coast (a review: an
   elevation-only stop's azimuth coast was 0, learned, and such stops pulled the azimuth
   coast's median to 0, its brake unwatched); nor has one whose turning was last seen
   ``settle_s`` or more before it (the motion machine's stillness: the stop that follows a
   turn the controller gave up, controller.py rule 12; an attack pass: a Prosistel
   power-cycled mid-turn, stopped 1.6 s after it stood, was learned a coast of 0). The coast
   goes the way the axis went last before the stop, not its net turn over that second (a
   review: a rotor turned back to a new target the other way and stopped within the second
   read a 1.5 degree coast as 0).
   Its speed is measured up to the stop it obeyed. The arrival error is of a move that came
   to rest by itself: not one stopped, stalled or ended by a new target while turning (it
   arrived nowhere).
4. A stall is the motion machine's; it is counted at the raw azimuth where it happened, or,
   the elevation's (motion.py rule 3: its axis), at the raw elevation, never at the azimuth
   (attack 25: an elevation jammed at 0 was counted at azimuth 190, where nothing held it).
5. A report is made only when a move ends (and at the start): statuses between moves carry
   the same report object, so nothing is published per poll. A controller that reports no
   position (DCU-1) has a report that says so and never another.
6. Cheap at every step: a motion already seen costs one comparison, a new one a few more and
   a reading appended while the rotor turns. A move keeps MAX_READINGS at most, so that its
   end is measured in well under a millisecond on the lines thread (house rule 12) however
   long it turned (a SPID tracking a pass for minutes, a noisy potentiometer "turning" for
   hours): once full, every other one of its older readings is dropped, the newest
   KEEP_RECENT kept whole (the stop and the coast are measured there). What is measured
   between two readings (a speed between band edges, a start set back at the move's speed)
   holds on the sparser readings.
7. A part that failed is ``rebuilt`` from its last memory (session.py rule 14); if even that
   fails (a bug in the judgement itself) it is built ``off_at`` its last report: it measures
   no more and that report stays, so it cannot fail again at every move and take the link
   down with it.
8. The odometer and the motor-on time leave out a still potentiometer's jitter (a degree
   either way at every poll while it waits to start and while it settles): only steps beyond
   the noise band count, and the motor is on until the last of them.
9. A speed is measured as the rotor's full speed: divided by the ``speed_factor`` of the
   controller settings in effect (a GS-232 at X2 turns at half speed: options.py rule 3), so
   a speed the user chose is no loss of speed; a move during which the factor changed gives
   no speed.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
from collections.abc import Mapping
from dataclasses import dataclass, field

from bridge.core.model import MotionState, RotatorHealth
from bridge.session import motion as mo
from bridge.session.config import WorkerConfig
from bridge.session.health_judge import Judge, Move

STEADY = (0.2, 0.8)  # rule 2
MIN_SPAN_S = 1.0
MIN_SPAN_DEG = 5.0
MAX_READINGS = 1_200  # rule 6: four minutes of readings at 0.2 s before thinning
KEEP_RECENT = 200  # rule 6
HEARD_SHARE = 0.8  # rule 3: a stop after which the rotor did not slow was not heard
SPEED_SPAN_S = 1.0  # rule 3: the speed a stop came at, over the readings of the second before
MAX_STOPS = 16  # a stop sent again (stops.py rule 2) a few times at most
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
    stop_t: float | None = None  # the first stop sent
    stops: list[float] = field(default_factory=list)  # every stop sent (rule 3: which took)
    from_rest: bool = True  # not a new target taken while turning (rule 3: no start delay)
    factor: float | None = 1.0  # rule 9: the speed factor throughout (None: it changed)


class Health:
    def __init__(
        self,
        cfg: WorkerConfig,
        memory: Mapping[str, object] | None = None,
        *,
        off_at: RotatorHealth | None = None,  # rule 7: measures no more; this report stays
    ) -> None:
        self._measured = cfg.spec.can_report_position and off_at is None
        self._wraps = cfg.spec.az_wraps
        self._has_el = cfg.spec.has_elevation
        self._noise_deg = cfg.motion.noise_deg  # rule 3
        self._resend_s = cfg.motion.stop_resend_s  # rule 3: a lost stop is sent again then
        self._settle_s = cfg.motion.settle_s  # rule 3: still this long before a stop: no coast
        self._judge = Judge(cfg.health, self._has_el, memory, wraps=self._wraps)
        if off_at is not None:
            self.report = off_at
        else:
            self.report = self._judge.report() if self._measured else RotatorHealth(measured=False)
        self._move: _Move | None = None
        self._changed_t: float | None = None
        self._stop_t: float | None = None
        self._seen: mo.Motion | None = None  # the motion last looked at
        self.speed_factor = 1.0  # rule 9: the session's, from the settings in effect

    def rebuilt(self, cfg: WorkerConfig) -> Health:
        """Rule 7: a new part from this one's last memory, or off at its last report."""
        try:
            return Health(cfg, self.report.memory)
        except Exception:  # the judgement itself fails
            return Health(cfg, off_at=self.report)

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
        if move is not None and move.factor != self.speed_factor:
            move.factor = None  # rule 9
        if m.changed_t is not None and m.changed_t != self._changed_t:
            self._changed_t = m.changed_t
            if move is not None and m.position_deg is not None:
                self._reading(move, m, m.changed_t, m.position_deg)
        if m.stop_sent_t is not None and m.stop_sent_t != self._stop_t:
            self._stop_t = m.stop_sent_t
            if move is not None and move.stop_t is None:
                move.stop_t = m.stop_sent_t
            if move is not None and len(move.stops) < MAX_STOPS:
                move.stops.append(m.stop_sent_t)
        if m.state is mo.MOVING and not (move is None and m.lost_turning):  # (taken for a turn
            # after a replug, none seen yet: no move until a reading shows one, motion.py rule 4)
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
        move.factor = self.speed_factor
        move.target_az, move.target_el = m.target_deg, m.el_target_deg
        move.readings.append((m.target_t or m.changed_t or 0.0, m.position_deg, m.el_position_deg))
        if m.target_t is None:  # the front panel: it has moved already (rule 3: no delay)
            move.first_change_t = m.changed_t
        self._move = move

    def _reading(self, move: _Move, m: mo.Motion, t: float, az: float) -> None:
        readings = move.readings
        readings.append((t, az, m.el_position_deg))
        if len(readings) >= MAX_READINGS:  # rule 6: the older part thinned, the first kept
            readings[:-KEEP_RECENT] = readings[:-KEEP_RECENT:2]
        if move.first_change_t is None and (
            az != move.from_az or m.el_position_deg != move.from_el
        ):
            move.first_change_t = t

    def _ended(self, move: _Move, m: mo.Motion) -> RotatorHealth | None:
        values: dict[str, float] = {}
        travel = [0.0, 0.0]
        last_moved_t = move.readings[0][0]
        az = self._unwrapped([r[1] for r in move.readings])
        axes: list[tuple[str, list[float]]] = [("az", az)]
        if self._has_el and all(r[2] is not None for r in move.readings):
            axes.append(("el", [r[2] for r in move.readings if r[2] is not None]))
        times = [r[0] for r in move.readings]
        for i, (axis, path) in enumerate(axes):
            travel[i], moved_t = _travel(times, path, self._noise_deg)
            last_moved_t = max(last_moved_t, moved_t)
            heard_t = _heard(times, path, move.stops, self._resend_s) if move.stops else None
            self._speed(axis, times, path, heard_t, values)
            if heard_t is not None and moved_t >= heard_t - self._settle_s:  # (rule 3)
                coast = _coast(times, path, heard_t)
                if coast is not None:
                    values[f"{axis}_coast"] = coast
        stalled = m.state is MotionState.STALLED
        el_stall = stalled and m.stalled == "elevation" and m.el_position_deg is not None
        turned = move.first_change_t is not None
        if move.target_t is not None and move.from_rest and move.first_change_t is not None:
            seen_turning = sum(1 for r in move.readings if r[0] > move.first_change_t) >= 2
            left_t = _left_t(times, axes, self._speeds(values, move.factor), self._noise_deg)
            if seen_turning and left_t is not None:  # not a silent slew's report (SatEL)
                values["delay"] = max(0.0, left_t - move.target_t)
        for key in [k for k in values if k.endswith(("_up", "_down"))]:  # rule 9
            if move.factor is None:
                del values[key]
            else:
                values[key] /= move.factor
        errors: list[float | None] = [None, None]
        at_rest = m.state is not MotionState.MOVING  # rule 3: not ended by a new target
        if at_rest and not stalled and move.stop_t is None and m.position_deg is not None:
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
            motor_on_s=max(0.0, last_moved_t - start_t) if turned else 0.0,
            stalled_at_deg=(m.el_position_deg if el_stall else m.position_deg) if stalled else None,
            stalled_axis="el" if el_stall else "az",
        )
        self._judge.add(done)
        self.report = self._judge.report()
        return self.report

    def _speeds(self, values: dict[str, float], factor: float | None) -> dict[str, float]:
        """Rule 3: the speeds a start is set back at: the move's own, else the judge's that
        way (full speeds, at the move's factor: rule 9)."""
        speeds = dict(values)
        for key in (f"{axis}_{way}" for axis in ("az", "el") for way in ("up", "down")):
            known = self._judge.known_speed(key)
            if key not in speeds and known is not None and factor is not None:
                speeds[key] = known * factor
        return speeds

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


def _travel(times: list[float], path: list[float], noise: float) -> tuple[float, float]:
    """Rule 8: the degrees turned and when the last turning was seen, a still potentiometer's
    jitter left out (steps within the noise band of where it last turned from count only
    once they add up beyond it; what is left at the end counts too)."""
    anchor, total, moved_t = path[0], 0.0, times[0]
    for t, a in zip(times, path, strict=True):
        if abs(a - anchor) > noise:
            total, anchor, moved_t = total + abs(a - anchor), a, t
    return total + abs(path[-1] - anchor), moved_t


def _heard(times: list[float], path: list[float], stops: list[float], resend_s: float) -> float:
    """Rule 3: the stop the rotor obeyed: the first after which it did not turn on, over the
    second half of the time until the next went out ``resend_s`` or more after it, at
    HEARD_SHARE of the speed it came at over SPEED_SPAN_S (it slowed: a coast; none went out
    so late: it is taken as obeyed); the last one sent otherwise."""
    for k, stop_t in enumerate(stops[:-1]):
        later = bisect_left(stops, stop_t + resend_s, k + 1)  # (motion.py's stop_again sum)
        if later == len(stops):
            return stop_t  # only stops sent sooner: too soon to tell a coast from a drive
        next_t = stops[later]
        came = _speed_over(times, path, stop_t - SPEED_SPAN_S, stop_t)
        went = _speed_over(times, path, (stop_t + next_t) / 2, next_t)
        if not came or went is None or went / came < HEARD_SHARE:
            return stop_t
    return stops[-1]


def _speed_over(times: list[float], path: list[float], t0: float, t1: float) -> float | None:
    """The speed between the first and the last reading within [t0, t1], if two are."""
    i, j = bisect_left(times, t0), bisect_right(times, t1) - 1  # (rule 6: times in order)
    if j <= i or times[j] <= times[i]:
        return None
    return (path[j] - path[i]) / (times[j] - times[i])


def _coast(times: list[float], path: list[float], stop_t: float) -> float | None:
    """Rule 3: from where the rotor was at the stop (the last reading before it, carried on
    at the speed of the two last) to where it came to rest, the way it was turning (its last
    step before the stop); None for an axis that was not turning then (over the second before
    the stop and the last reading before it)."""
    j = bisect_right(times, stop_t) - 1  # (rule 6: times in order)
    if j < 1:
        return None
    since = min(j - 1, max(0, bisect_right(times, stop_t - SPEED_SPAN_S) - 1))
    if path[j] == path[since]:
        return None  # an elevation-only move's azimuth, an axis that had arrived
    last = j  # its last step: a rotor turned back within that second goes the way it went last
    while path[last] == path[last - 1]:  # (one came after ``since``: the second's readings)
        last -= 1
    i = j - 1
    dt = times[j] - times[i]
    speed = (path[j] - path[i]) / dt if dt > 0 else 0.0
    at_stop = path[j] + speed * (stop_t - times[j])
    way = 1.0 if path[last] > path[last - 1] else -1.0
    return max(0.0, (path[-1] - at_stop) * way)


def _left_t(
    times: list[float], axes: list[tuple[str, list[float]]], speeds: dict[str, float], noise: float
) -> float | None:
    """Rule 3: when the rotor left where it stood (the first reading beyond the noise band on
    either axis, set back by the way it had gone at the speed that way; none known: None)."""
    for k, t in enumerate(times):
        for axis, path in axes:
            gone = path[k] - path[0]
            if abs(gone) > noise:
                speed = speeds.get(f"{axis}_{'up' if gone > 0 else 'down'}")
                return t - abs(gone) / speed if speed else None
    return None
