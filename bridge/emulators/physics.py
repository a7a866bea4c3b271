"""Motion physics of one rotator axis, shared by every controller emulator.

What the device is: the mechanical part of a rotator (motor, gears, stops, position sensor) seen
from its controller. A controller emulator owns one `Axis` per axis (azimuth; elevation for the
SatEL/SPID families) and decides *when* to move; the axis only knows *how* it moves.

Frame: none (no wire here). Angles are degrees, speeds degrees per second, times seconds.

Source documents: the Idiom Press Rotor-EZ texts and Hamlib's rotorez notes (Hy-Gain rotors
turn 0..360 against an end stop, so the short way round is not always available; a rotator can
get stuck; an operator can turn it from the front panel).

Rules:
1. Pure: no clock and no threads. Every method that depends on time takes `now` (seconds).
   A `now` earlier than the last one seen is treated as the last one seen.
2. Travel is linear between `min_deg` and `max_deg` and never wraps: 10 -> 350 on a 0..360 rotor
   goes the long way through 180. A target outside the range is clamped to the nearest stop.
3. Constant speed, no acceleration. `arrival_time_s()` is exact and `advance()` returns the
   instant of arrival, so a controller can start a brake delay at the true arrival time however
   late it looks. The only deceleration is a coast a controller asks for (rule 6).
4. A jammed axis keeps its motor running (`is_moving` stays True) but its position does not
   change, and it never arrives. Unjamming resumes the move from where it stuck.
5. Every move records who drives it (`driver`): a controller command or the front panel
   ("panel"). A new move replaces the current one at once; the axis has no opinion on whether
   that is wise (controllers decide, e.g. the Rotor-EZ refuses to re-target while turning).
6. `stop(now, coast_deg=, coast_s=)` may let the rotor run on after its motor is cut (momentum,
   a motor's ramp): up to `coast_deg` further in the direction it was turning, never past a
   limit, decelerating uniformly to rest in `coast_s` (x(t) = D * (1 - (1 - t/T)^2)). The motor
   is off meanwhile (`is_moving` False, no target, no arrival) but `is_coasting` is True and
   the position changes; `coast_end_s()` says when it rests. A new move, a jam or
   `set_position` ends a coast where it is; a stop during one changes nothing. A jammed axis
   does not coast.
"""

from __future__ import annotations

import math

DRIVER_COMMAND = "command"
DRIVER_PANEL = "panel"


class Axis:
    """One axis with linear travel between two mechanical stops."""

    def __init__(
        self,
        position_deg: float = 0.0,
        *,
        min_deg: float = 0.0,
        max_deg: float = 360.0,
        speed_deg_s: float = 6.0,
        now: float = 0.0,
    ) -> None:
        if not min_deg < max_deg:
            raise ValueError(f"min_deg ({min_deg}) must be below max_deg ({max_deg})")
        if not speed_deg_s > 0:
            raise ValueError(f"speed_deg_s must be positive, got {speed_deg_s}")
        if not min_deg <= position_deg <= max_deg:
            raise ValueError(f"position_deg {position_deg} outside {min_deg}..{max_deg}")
        self.min_deg: float = float(min_deg)
        self.max_deg: float = float(max_deg)
        self.speed_deg_s: float = float(speed_deg_s)
        self._position_deg: float = float(position_deg)
        self._anchor_s: float = now
        self._target_deg: float | None = None
        self._driver: str | None = None
        self._jammed: bool = False
        self._coast: tuple[float, float, float, float] | None = None  # from, to, start, length

    # -- read-only view -------------------------------------------------------------------------

    @property
    def position_deg(self) -> float:
        """Position as of the last `advance()` (or mutation); use position_deg_at() for now."""
        return self._position_deg

    @property
    def target_deg(self) -> float | None:
        return self._target_deg

    @property
    def driver(self) -> str | None:
        return self._driver

    @property
    def is_moving(self) -> bool:
        """The motor runs (also while jammed). Call advance(now) first for an up-to-date answer."""
        return self._target_deg is not None

    @property
    def is_jammed(self) -> bool:
        return self._jammed

    @property
    def is_coasting(self) -> bool:
        """Running on with the motor off (rule 6). Call advance(now) first."""
        return self._coast is not None

    def coast_end_s(self) -> float | None:
        """When the current coast comes to rest, or None."""
        coast = self._coast
        return None if coast is None else coast[2] + coast[3]

    def clamp(self, az_deg: float) -> float:
        return min(self.max_deg, max(self.min_deg, float(az_deg)))

    def position_deg_at(self, now: float) -> float:
        """Where the axis is at `now`, without committing anything."""
        coast = self._coast
        if coast is not None:
            start_deg, end_deg, start_s, length_s = coast
            left = 1.0 - min(1.0, max(0.0, now - start_s) / length_s)
            return start_deg + (end_deg - start_deg) * (1.0 - left * left)
        target = self._target_deg
        if target is None or self._jammed:
            return self._position_deg
        travel_deg = self.speed_deg_s * max(0.0, now - self._anchor_s)
        distance_deg = target - self._position_deg
        if abs(distance_deg) <= travel_deg:
            return target
        return self._position_deg + math.copysign(travel_deg, distance_deg)

    def arrival_time_s(self) -> float | None:
        """When the current move ends, or None (idle or jammed)."""
        target = self._target_deg
        if target is None or self._jammed:
            return None
        return self._anchor_s + abs(target - self._position_deg) / self.speed_deg_s

    # -- time -----------------------------------------------------------------------------------

    def advance(self, now: float) -> float | None:
        """Commit the position at `now`; return the arrival instant if the move ended by then."""
        now = max(now, self._anchor_s)
        arrival_s = self.arrival_time_s()
        self._position_deg = self.position_deg_at(now)
        self._anchor_s = now
        coast = self._coast
        if coast is not None and coast[2] + coast[3] <= now:
            self._position_deg = coast[1]  # at rest exactly where the coast ends
            self._coast = None
        if arrival_s is not None and arrival_s <= now:
            assert self._target_deg is not None
            self._position_deg = self._target_deg  # exactly there, whatever the float rounding
            self._target_deg = None
            self._driver = None
            return arrival_s
        return None

    # -- commands -------------------------------------------------------------------------------

    def start_move(self, target_deg: float, now: float, *, driver: str = DRIVER_COMMAND) -> bool:
        """Head for `target_deg` (clamped). Return False, and stay idle, if already there."""
        self.advance(now)
        self._coast = None
        target = self.clamp(target_deg)
        if target == self._position_deg:
            self._target_deg = None
            self._driver = None
            return False
        self._target_deg = target
        self._driver = driver
        return True

    def manual_move(self, target_deg: float, now: float) -> bool:
        """The front panel's pointing control: an ordinary move driven by the panel."""
        return self.start_move(target_deg, now, driver=DRIVER_PANEL)

    def stop(self, now: float, *, coast_deg: float = 0.0, coast_s: float = 0.0) -> bool:
        """Cut the motor, and let the rotor coast (rule 6). Return True if it was running."""
        self.advance(now)
        target = self._target_deg
        self._target_deg = None
        self._driver = None
        if target is None:
            return False
        if coast_deg > 0 and coast_s > 0 and not self._jammed:
            end_deg = self.clamp(
                self._position_deg + math.copysign(coast_deg, target - self._position_deg)
            )
            if end_deg != self._position_deg:
                self._coast = (self._position_deg, end_deg, now, float(coast_s))
        return True

    def jam(self, now: float) -> None:
        """From `now` on the motor may run but the position stays (rule 4)."""
        self.advance(now)
        self._coast = None
        self._jammed = True

    def unjam(self, now: float) -> None:
        self.advance(now)
        self._jammed = False

    def set_position(self, az_deg: float, now: float) -> None:
        """Put the axis somewhere, motor off (test set-up, not physics)."""
        self.advance(now)
        self._coast = None
        self._position_deg = self.clamp(az_deg)
        self._target_deg = None
        self._driver = None
