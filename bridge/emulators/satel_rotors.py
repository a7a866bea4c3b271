"""The SatEL's two rotors and the slew that drives them: the motion half of satel.py.

What the device is: see satel.py. Azimuth turns 0..360 (break at north), elevation 0..90, each
through relays at its own constant speed (one physics.Axis per rotor).

Source documents: satel.py's (its speeds are assumptions); nothing here comes from bridge/protocols.

Rules:
1. A slew (satel.py rule 2) starts both axes at once toward targets clamped to the stops (the
   controller checks nothing); it lasts until the last moving axis arrives, and never ends while
   one is jammed.
2. Ending a slew or stopping halts both axes where they are, whoever drives them.
3. No output, no log, no opinion: satel.py decides when a slew may start, what its end prints
   and what is recorded.
"""

from __future__ import annotations

from dataclasses import dataclass

from bridge.emulators.physics import Axis


@dataclass(frozen=True)
class Slew:
    kind: str  # DRIVER_COMMAND (`p`, reports at the end) or satel.DRIVER_EPHEMERIS (silent)
    az_deg: float
    el_deg: float


class Rotors:
    """Azimuth and elevation, and the slew running on them (if any)."""

    def __init__(
        self, az_deg: float, el_deg: float, az_speed_deg_s: float, el_speed_deg_s: float, now: float
    ) -> None:
        self.az = Axis(az_deg, min_deg=0.0, max_deg=360.0, speed_deg_s=az_speed_deg_s, now=now)
        self.el = Axis(el_deg, min_deg=0.0, max_deg=90.0, speed_deg_s=el_speed_deg_s, now=now)
        self.slew: Slew | None = None

    @property
    def is_moving(self) -> bool:
        return self.az.is_moving or self.el.is_moving

    def positions_deg_at(self, now: float) -> tuple[float, float]:
        return self.az.position_deg_at(now), self.el.position_deg_at(now)

    def start_slew(self, kind: str, az_deg: float, el_deg: float, now: float) -> Slew:
        """Head both axes for az/el (clamped, rule 1); the slew is over at once if neither moves."""
        slew = self.slew = Slew(kind, self.az.clamp(az_deg), self.el.clamp(el_deg))
        self.az.start_move(slew.az_deg, now, driver=kind)
        self.el.start_move(slew.el_deg, now, driver=kind)
        return slew

    def slew_end_s(self, now: float) -> float | None:
        """When the running slew ends (`now` if nothing moves), None if never (jammed)."""
        arrivals = [axis.arrival_time_s() for axis in (self.az, self.el) if axis.is_moving]
        if any(t is None for t in arrivals):
            return None
        return max([t for t in arrivals if t is not None], default=now)

    def end_slew(self, now: float) -> Slew | None:
        """Halt both axes (rule 2) and forget the slew; the one that ran, if any."""
        slew, self.slew = self.slew, None
        self.stop(now)
        return slew

    def stop(self, now: float) -> bool:
        """Halt both axes (rule 2); True if either was turning."""
        return any([self.az.stop(now), self.el.stop(now)])  # a list: stop both

    def advance(self, now: float) -> list[str]:
        """Commit the positions at `now`; the names of the axes whose move ended by then."""
        axes = (("az", self.az), ("el", self.el))
        return [name for name, axis in axes if axis.advance(now) is not None]  # 0.0 is an arrival

    def jam(self, now: float) -> None:
        self.az.jam(now)
        self.el.jam(now)

    def unjam(self, now: float) -> None:
        self.az.unjam(now)
        self.el.unjam(now)
