"""Review 74: since d241d535 an RC2800's stop always begins with the azimuth (``A`` CR ``S`` CR),
written once the box's 200 ms between its axes allows, the elevation's ``E`` CR ``S`` CR the gap
after it (rc2800.py rule 9: "the azimuth is the axis a user turns most"). An RC2800 az/el can
be a composite's elevation box (protocols/axes.py rule 2, ``ElevationOnly``): there its azimuth
never turns, and the elevation is the only axis moving. A STOP shortly after an ``E`` CR poll
then stops the elevation up to two gaps late: the azimuth's frame waits out the rest of the gap
since the ``E``, and the elevation's goes 200 ms after that, where a stop to the elevation
needs no wait at all after a frame to it (helper-590's, d241d535^, wrote ``E`` CR ``S`` CR at
once). In virtual time (tests/engine/virtual_composite.py)."""

from __future__ import annotations

from bridge.core.model import Target
from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite

BOXES = {Axis.ELEVATION: {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}}
STOP_AFTER_E_S = 0.05  # the STOP comes this long after the elevation box's E CR poll
SLACK_S = 0.02  # a few byte times at 9600 baud
RUN_ON_DEG = 0.3  # the elevation's coast at 3 degrees a second if its stop goes at once


def online(v: VirtualComposite) -> bool:
    return v.status.available


def test_an_rc2800_elevation_box_stops_its_elevation_at_once_after_an_e_poll() -> None:
    with VirtualComposite("rt21", "rc2800", emulators=BOXES) as v:
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(None, 80.0))  # the elevation alone turns (the RC2800's azimuth never does)
        el = v.el
        v.run_until(lambda h: h.el.truth().is_moving and h.el.truth().el_deg > 10, 60, "turning")
        v.run_until(
            lambda h: el.writes[-1].data == b"E\r" and el.writes[-1].t == h.now, 5, "E asked"
        )
        e_t = v.now
        v.run_for(STOP_AFTER_E_S)
        assert el.writes[-1].t == e_t and el.truth().is_moving  # the line quiet since that E CR
        stop_t, el_at_stop = v.now, el.truth().el_deg
        v.stop()
        v.run_until(lambda h: not h.el.truth().is_moving, 10, "stopped")
        el_stop = [w.t for w in el.writes if w.t >= stop_t and b"E\rS\r" in w.data]
        assert el_stop and el_stop[0] <= stop_t + SLACK_S, [
            (round(w.t - stop_t, 3), w.data) for w in el.writes if w.t >= e_t
        ]
        assert el.truth().too_soon == 0  # the box's axis gap kept
        assert el.truth().el_deg - el_at_stop < RUN_ON_DEG
