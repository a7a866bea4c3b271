"""A slew: a move on a controller that is silent until it ends (SatEL), as far as it can be known.

Source: protocols/satel.md (the controller answers nothing while it moves and reports its
position once the move is over). What is known: where it started (the last reading, if any),
where it goes, when, at which speeds the rotor turns; so how long it should take, and where the
rotor should be meanwhile (an estimate, marked as one in the status).

Rules:
1. Travel time is the slower axis's; an unknown start costs the whole span; the azimuth travels
   linearly between its stops (no wrap through north).
2. Its report is owed until SLEW_TIME_FACTOR times the travel time plus SLEW_MARGIN_S.
3. The estimate moves from the start at the configured speeds in whole degrees and never passes
   the target.
"""

from __future__ import annotations

from dataclasses import dataclass

from bridge.model import Source

SLEW_TIME_FACTOR = 2.0  # a slew's report is waited for twice the travel time at the set speeds...
SLEW_MARGIN_S = 5.0  # ...plus this (relays, start-up, the report itself at 9600 baud)


@dataclass(frozen=True)
class Slew:
    """A move on a controller that is silent until it ends: what we know to estimate it."""

    start_t: float
    from_az_deg: float | None
    from_el_deg: float | None
    to_az_deg: float
    to_el_deg: float | None
    source: Source = Source.MQTT
    stops: int = 0  # stops written during the slew
    attempt: int = 1  # 2: the same target sent again after its report did not come

    def travel_s(
        self, az_speed_deg_s: float, el_speed_deg_s: float, az_span_deg: float, el_span_deg: float
    ) -> float:
        """How long the slew takes at these speeds: the slower axis decides. Where the start is
        unknown, the whole span; the azimuth travels linearly between its stops."""
        az_travel = _travel(self.from_az_deg, self.to_az_deg, az_span_deg)
        el_travel = _travel(self.from_el_deg, self.to_el_deg, el_span_deg)
        return max(az_travel / az_speed_deg_s, el_travel / el_speed_deg_s)

    def estimate(
        self, now: float, az_speed_deg_s: float, el_speed_deg_s: float
    ) -> tuple[float | None, float | None]:
        """Where the rotor should be, in whole degrees, moving at the nominal speeds."""
        dt = now - self.start_t
        return (
            _toward(self.from_az_deg, self.to_az_deg, az_speed_deg_s * dt),
            _toward(self.from_el_deg, self.to_el_deg, el_speed_deg_s * dt),
        )


def _travel(start: float | None, end: float | None, span: float) -> float:
    if end is None:
        return 0.0
    return span if start is None else abs(end - start)


def _toward(start: float | None, end: float | None, step: float) -> float | None:
    if start is None or end is None:
        return end
    if abs(end - start) <= step:
        return end
    return float(round(start + step * (1 if end > start else -1)))
