"""Rotor health's memory and its judgement: what the finished moves (health.py) add up to, the
baseline they are judged against, and the warnings. Pure: no clock, no I/O; what it keeps is
plain JSON data (``memory``), which the state file holds across restarts.

Rules:
1. A baseline per metric (speed each way per axis, start delay, coast per axis) is the median
   of the values seen over the first ``baseline_moves`` moves (after a reset too); a metric
   with fewer than MIN_VALUES values by then is learned from the moves after, until it has
   them. Speeds set in the settings (``az_speed_deg_s``, ``el_speed_deg_s``) are the speed
   baseline, both ways, from the start; taken out of the settings, the speeds are learned.
2. A warning judges the median of each metric's last WINDOW values (a speed: the last WINDOW
   moves that way; the coast: the last WINDOW stops), with at least MIN_VALUES of them, never
   one move: a gust or one noisy reading never warns. Per metric, not "the metric's values
   among the last moves": a rotor turned mostly one way would leave three values at times for
   the other, and a median of three is not steady enough to judge by.
   A speed more than ``speed_drop_pct`` below its baseline warns; so do the two directions of
   an axis more than that apart (and by half of it more than at the baseline: a rotor that
   always turned one way faster is no news), a start delay or a coast grown by more than that
   (and by more than DELAY_FLOOR_S, COAST_FLOOR_DEG: a small value doubling is no news).
   With moves varying by +-10 % at random, no median strays 20 % from another: no warning.
3. Stalls warn when they repeat at one azimuth: STALL_REPEATS of the last STALL_MEMORY within
   STALL_NEAR_DEG of each other (on a scale that wraps, 359 and 1 are 2 apart; on one that
   goes past 360, 370 is another place than 10). Single stalls scattered round the circle do
   not. A stall of the elevation (the motion machine's stalled axis, motion.py rule 3: jammed
   while the azimuth turned on or had come) is kept at its elevation, apart (``stall_el_at``),
   and warns the same way: never at the azimuth, where nothing held the rotor (attack 25).
4. A warning names what changed and by how much, in words a user reads on a dashboard.
5. A reset starts a new baseline and forgets the recent moves and stalls; the totals (moves,
   stalls, odometer, motor-on time) go on: they only ever grow.
6. A memory that cannot be read (another version, a hand edit) is logged and replaced by a
   fresh one: health is never a reason not to start. A number that is no finite float (an
   integer too large for one, NaN, Infinity, which Python's JSON reads) is unreadable: it
   would otherwise reach ``R/health`` as ``Infinity``, which no JSON parser takes. So is one
   no move could have given (BOUNDS: a speed not above 0 or beyond the settings' 360 °/s, a
   negative start delay, coast, total or arrival error, a stall far off any scale, a count
   beyond 2**53, which a JSON reader takes back inexactly): a review found a negative
   baseline start delay or coast kept, which warned at every move, a huge speed that warned
   for good, and a zero or negative one under which the rotor's slowing went unseen for good.
   What is learning is kept to what ``_learn`` keeps (twice ``baseline_moves`` values). A move
   that measured such a value (a corrupt path, a garbled scale) adds it nowhere (its stall is
   still counted, not its place): the memory must read back.
"""

from __future__ import annotations

import logging
import math
import statistics
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from bridge.core.model import AxisHealth, RotatorHealth
from bridge.session.config import HealthConfig

log = logging.getLogger(__name__)

WINDOW = 7  # rule 2: a drop one way shows within 8 moves turned both ways in turn
MIN_VALUES = 3
DELAY_FLOOR_S = 0.5
COAST_FLOOR_DEG = 2.0
STALL_MEMORY = 20  # rule 3
STALL_REPEATS = 3
STALL_NEAR_DEG = 5.0
MEMORY_VERSION = 1
MAX_COUNT = 2**53  # rule 6
MAX_SPEED_DEG_S = 360.0  # the settings' az_speed_deg_s and el_speed_deg_s at most
MAX_DELAY_S = 600.0  # the settings' stall_timeout_s at most: a longer start is a stall
MAX_DEG = 720.0  # a coast, an arrival error: more than any controller's scale
STALL_SCALE_DEG = (-360.0, 720.0)  # every controller's raw azimuths (SPID's -180..540)

SPEEDS = ("az_up", "az_down", "el_up", "el_down")
COASTS = ("az_coast", "el_coast")
METRICS = (*SPEEDS, "delay", *COASTS)
BOUNDS = {  # rule 6: what a move can give, (lowest, highest, the lowest excluded)
    **dict.fromkeys(SPEEDS, (0.0, MAX_SPEED_DEG_S, True)),
    "delay": (0.0, MAX_DELAY_S, False),
    **dict.fromkeys(COASTS, (0.0, MAX_DEG, False)),
}
NAMES = {
    "az_up": "clockwise",
    "az_down": "counter-clockwise",
    "el_up": "elevation up",
    "el_down": "elevation down",
    "az_coast": "coast after a stop",
    "el_coast": "elevation coast after a stop",
}


@dataclass(frozen=True)
class Move:
    """One finished move as health.py measured it; a value it could not measure is absent."""

    values: dict[str, float] = field(default_factory=dict)  # METRICS keys
    travel_deg: tuple[float, float] = (0.0, 0.0)  # az, el
    arrival_error_deg: tuple[float | None, float | None] = (None, None)
    motor_on_s: float = 0.0
    stalled_at_deg: float | None = None
    stalled_axis: str = "az"  # rule 3: "el": ``stalled_at_deg`` is the elevation


def _median(values: list[float]) -> float | None:
    return statistics.median(values) if len(values) >= MIN_VALUES else None


def _floats(raw: object) -> list[float]:
    if not isinstance(raw, list) or not all(
        isinstance(v, int | float) and not isinstance(v, bool) for v in raw
    ):
        raise ValueError("not a list of numbers")
    try:
        out = [float(v) for v in raw]
    except OverflowError:
        raise ValueError("a number too large") from None
    if not all(math.isfinite(v) for v in out):  # rule 6
        raise ValueError("a number that is not finite")
    return out


class Judge:
    def __init__(
        self,
        cfg: HealthConfig,
        has_elevation: bool,
        memory: Mapping[str, object] | None = None,
        *,
        wraps: bool = False,  # the azimuth scale wraps at 360 (rule 3)
    ) -> None:
        self._cfg = cfg
        self._el = has_elevation
        self._wraps = wraps
        self._fresh()
        if memory:
            try:
                self._restore(memory)
            except (KeyError, TypeError, ValueError) as exc:  # rule 6
                log.error("rotor health's memory unreadable (%s): starting afresh", exc)
                self._fresh()

    def _fresh(self) -> None:
        self.moves = 0
        self.stalls = 0
        self.motor_on_s = 0.0
        self.odometer_deg = [0.0, 0.0]
        self.last_coast: list[float | None] = [None, None]
        self.last_error: list[float | None] = [None, None]
        self._new_baseline()

    def _new_baseline(self) -> None:
        """Rule 1 (and rule 5: what a reset forgets)."""
        self.baseline: dict[str, float | None] = dict.fromkeys(METRICS)
        self.learned = 0  # moves learned from since the baseline started
        self.learning: dict[str, list[float]] = {k: [] for k in METRICS}
        self.recent: dict[str, list[float]] = {k: [] for k in METRICS}  # the last WINDOW each
        self.stall_at: list[float] = []
        self.stall_el_at: list[float] = []  # rule 3: the elevation's stalls
        self.from_settings = False
        for axis, speed in (("az", self._cfg.az_speed_deg_s), ("el", self._cfg.el_speed_deg_s)):
            if speed is not None:
                self.baseline[f"{axis}_up"] = self.baseline[f"{axis}_down"] = speed
                self.from_settings = True

    def reset(self) -> None:
        self._new_baseline()

    # -- a move -----------------------------------------------------------------------------
    def add(self, move: Move) -> None:
        values = {k: v for k, v in move.values.items() if _fits(v, *BOUNDS[k])}  # rule 6
        if values != move.values:
            move = replace(move, values=values)
        self.moves += 1
        self.motor_on_s += move.motor_on_s
        for i in (0, 1):
            self.odometer_deg[i] += move.travel_deg[i]
            error = move.arrival_error_deg[i]
            if error is not None and _fits(error, 0.0, MAX_DEG):  # rule 6
                self.last_error[i] = error
        if move.stalled_at_deg is not None:
            self.stalls += 1
            if not _fits(move.stalled_at_deg, *STALL_SCALE_DEG):  # rule 6
                pass
            elif move.stalled_axis == "el":  # rule 3: at its elevation
                self.stall_el_at = [*self.stall_el_at, move.stalled_at_deg][-STALL_MEMORY:]
            else:
                self.stall_at = [*self.stall_at, move.stalled_at_deg][-STALL_MEMORY:]
        for i, key in enumerate(COASTS):
            coast = move.values.get(key)
            if coast is not None:
                self.last_coast[i] = coast
        for key, value in move.values.items():
            self.recent[key] = [*self.recent[key], value][-WINDOW:]
        self._learn(move)

    def _learn(self, move: Move) -> None:
        """Rule 1."""
        self.learned += 1
        for key, value in move.values.items():
            if self.baseline.get(key) is None:
                self.learning[key] = [*self.learning[key], value][-2 * self._cfg.baseline_moves :]
        if self.learned < self._cfg.baseline_moves:
            return
        for key, values in self.learning.items():
            if self.baseline[key] is None and len(values) >= MIN_VALUES:
                self.baseline[key] = statistics.median(values)
                self.learning[key] = []

    # -- what the recent moves say ------------------------------------------------------------
    def recent_median(self, key: str) -> float | None:
        return _median(self.recent[key])

    def known_speed(self, key: str) -> float | None:
        """A speed the moves so far give (the recent ones', else the baseline's): health.py
        rule 3 sets a short move's start back at it."""
        speed = self.recent_median(key)
        return speed if speed is not None else self.baseline[key]

    def warnings(self) -> list[str]:
        """Rules 2-4."""
        out: list[str] = []
        pct = self._cfg.speed_drop_pct
        over = f"over the last {WINDOW} moves each way"
        for key in SPEEDS:
            now, base = self.recent_median(key), self.baseline[key]
            if now is not None and base and now < base * (1 - pct / 100):
                drop = 100 * (base - now) / base
                out.append(
                    f"{NAMES[key]} {now:.1f} °/s, {drop:.0f} % below its baseline {base:.1f} "
                    f"over its last {len(self.recent[key])} moves"
                )
        for axis in ("az", "el"):
            out += self._apart(axis, pct, over)
        delay, base = self.recent_median("delay"), self.baseline["delay"]
        if delay is not None and base is not None and _grown(delay, base, pct, DELAY_FLOOR_S):
            out.append(
                f"start delay {delay:.1f} s, {delay - base:.1f} s longer than its baseline "
                f"{base:.1f} over the last {len(self.recent['delay'])} moves"
            )
        for key in COASTS:
            coast, base = self.recent_median(key), self.baseline[key]
            if coast is not None and base is not None and _grown(coast, base, pct, COAST_FLOOR_DEG):
                out.append(
                    f"{NAMES[key]} {coast:.1f}°, {coast - base:.1f}° more than its baseline "
                    f"{base:.1f} over the last {len(self.recent[key])} stops"
                )
        return out + self._stall_warnings() + self._stall_warnings(elevation=True)

    def _apart(self, axis: str, pct: float, over: str) -> list[str]:
        up, down = self.recent_median(f"{axis}_up"), self.recent_median(f"{axis}_down")
        b_up, b_down = self.baseline[f"{axis}_up"], self.baseline[f"{axis}_down"]
        if not (up and down and b_up and b_down):
            return []
        now_pct = 100 * abs(up - down) / max(up, down)
        base_pct = 100 * abs(b_up - b_down) / max(b_up, b_down)
        if now_pct <= max(pct, base_pct + pct / 2):  # rule 2: a rotor that always was lopsided
            return []
        return [
            f"{NAMES[axis + '_up']} {up:.1f} °/s and {NAMES[axis + '_down']} {down:.1f} °/s, "
            f"{now_pct:.0f} % apart ({base_pct:.0f} % at the baseline) {over}"
        ]

    def _stall_warnings(self, *, elevation: bool = False) -> list[str]:
        """Rule 3: one warning per place the stalls repeat at (the elevation's apart)."""
        out: list[str] = []
        kept = self.stall_el_at if elevation else self.stall_at
        wraps = self._wraps and not elevation
        left = list(kept)
        while left:
            here = left[0]
            near = [a for a in left if self._apart_deg(a, here, wraps) <= STALL_NEAR_DEG]
            if len(near) >= STALL_REPEATS:
                where = here if wraps else statistics.median(near)  # no median across 0
                place = f"elevation {where:.0f}°" if elevation else f"{where:.0f}°"
                out.append(
                    f"{len(near)} stalls near {place} (within {STALL_NEAR_DEG:g}°) among the "
                    f"last {len(kept)}: something holds the rotor there"
                )
                left = [a for a in left if self._apart_deg(a, where, wraps) > STALL_NEAR_DEG]
            else:
                left = left[1:]
        return out

    @staticmethod
    def _apart_deg(a: float, b: float, wraps: bool) -> float:
        """Rule 3: raw azimuths, on a scale that wraps or not (an elevation's never wraps)."""
        d = abs(a - b)
        return min(d, 360.0 - d) if wraps and d > 180.0 else d

    # -- what it tells and keeps ----------------------------------------------------------------
    def report(self) -> RotatorHealth:
        axes = [self._axis(i, axis) for i, axis in enumerate(("az", "el"))]
        if self.from_settings:
            source = "settings"
        else:
            source = "learned" if self.learned >= self._cfg.baseline_moves else "learning"
        return RotatorHealth(
            az=axes[0],
            el=axes[1] if self._el else None,
            start_delay_s=self.recent_median("delay"),
            baseline_start_delay_s=self.baseline["delay"],
            baseline_from=source,
            baseline_moves_left=max(0, self._cfg.baseline_moves - self.learned),
            moves=self.moves,
            stalls=self.stalls,
            stall_azimuths_deg=tuple(self.stall_at),
            stall_elevations_deg=tuple(self.stall_el_at),
            motor_on_s=self.motor_on_s,
            warnings=tuple(self.warnings()),
            memory=self.memory(),
        )

    def _axis(self, i: int, axis: str) -> AxisHealth:
        return AxisHealth(
            speed_up_deg_s=self.recent_median(f"{axis}_up"),
            speed_down_deg_s=self.recent_median(f"{axis}_down"),
            baseline_up_deg_s=self.baseline[f"{axis}_up"],
            baseline_down_deg_s=self.baseline[f"{axis}_down"],
            coast_deg=self.last_coast[i],
            baseline_coast_deg=self.baseline[f"{axis}_coast"],
            arrival_error_deg=self.last_error[i],
            odometer_deg=self.odometer_deg[i],
        )

    def memory(self) -> dict[str, object]:
        return {
            "version": MEMORY_VERSION,
            "moves": self.moves,
            "stalls": self.stalls,
            "motor_on_s": self.motor_on_s,
            "odometer_deg": list(self.odometer_deg),
            "last_coast_deg": list(self.last_coast),
            "last_error_deg": list(self.last_error),
            "baseline": dict(self.baseline),
            "from_settings": self.from_settings,
            "learned": self.learned,
            "learning": {k: list(v) for k, v in self.learning.items() if v},
            "recent": {k: list(v) for k, v in self.recent.items() if v},
            "stall_at": list(self.stall_at),
            "stall_el_at": list(self.stall_el_at),
        }

    def _restore(self, memory: Mapping[str, object]) -> None:
        """Rule 6: ValueError, KeyError or TypeError for anything not as ``memory`` writes it."""
        if memory.get("version") != MEMORY_VERSION:
            raise ValueError(f"version {memory.get('version')!r}")
        self.moves, self.stalls = _count(memory["moves"]), _count(memory["stalls"])
        self.motor_on_s = _within(_floats([memory["motor_on_s"]]), 0.0, math.inf)[0]
        self.odometer_deg = _within(_floats(memory["odometer_deg"]), 0.0, math.inf)
        self.last_coast = _maybe_floats(memory["last_coast_deg"], 0.0, MAX_DEG)
        self.last_error = _maybe_floats(memory["last_error_deg"], 0.0, MAX_DEG)
        if len(self.odometer_deg) != 2 or len(self.last_coast) != 2 or len(self.last_error) != 2:
            raise ValueError("not two axes")
        baseline, learning, recent = memory["baseline"], memory["learning"], memory["recent"]
        if not all(isinstance(t, dict) for t in (baseline, learning, recent)):
            raise ValueError("baseline, learning or recent is not a table")
        assert isinstance(baseline, dict) and isinstance(learning, dict)
        assert isinstance(recent, dict)
        kept = {k: _maybe_floats([baseline.get(k)], *BOUNDS[k])[0] for k in METRICS}
        if memory["from_settings"] is True:  # rule 1: the speeds set then, not kept if no
            kept.update(dict.fromkeys(SPEEDS))  # longer set: learned from the moves after
        kept.update({k: v for k, v in self.baseline.items() if v is not None})  # set now: win
        self.baseline = kept
        self.learned = _count(memory["learned"])
        most = 2 * self._cfg.baseline_moves  # (what _learn keeps)
        self.learning = {
            k: _within(_floats(learning.get(k, [])), *BOUNDS[k])[-most:] for k in METRICS
        }
        self.recent = {
            k: _within(_floats(recent.get(k, [])), *BOUNDS[k])[-WINDOW:] for k in METRICS
        }
        self.stall_at = _within(_floats(memory["stall_at"]), *STALL_SCALE_DEG)[-STALL_MEMORY:]
        el_at = _floats(memory.get("stall_el_at", []))  # (absent in a memory written before)
        self.stall_el_at = _within(el_at, *STALL_SCALE_DEG)[-STALL_MEMORY:]


def _count(raw: object) -> int:
    if isinstance(raw, bool) or not isinstance(raw, int) or not 0 <= raw <= MAX_COUNT:
        raise ValueError("no count")  # (not its digits: one too long to print raises)
    return raw


def _fits(value: float, lo: float, hi: float, above: bool = False) -> bool:
    """Rule 6: a value a move could have given (``above``: lo excluded)."""
    return (lo < value if above else lo <= value) and value <= hi


def _within(values: list[float], lo: float, hi: float, above: bool = False) -> list[float]:
    """Rule 6: values a move could have given, or ValueError."""
    if not all(_fits(v, lo, hi, above) for v in values):
        raise ValueError(f"a value outside {lo:g}..{hi:g}")
    return values


def _maybe_floats(raw: object, lo: float, hi: float, above: bool = False) -> list[float | None]:
    if not isinstance(raw, list):
        raise ValueError("not a list")
    return [None if v is None else _within(_floats([v]), lo, hi, above)[0] for v in raw]


def _grown(now: float, base: float, pct: float, floor: float) -> bool:
    return now > base * (1 + pct / 100) and now > base + floor
