"""Attack 19: a Prosistel D on an elevation rotor, on its own (``prosistel-el``: "its elevation
is that rotator's bearing, the box has no azimuth", protocols/prosistel.py), takes ``R/track``
and ``R/follow wsjtx`` like an azimuth rotor, and each sends it an azimuth: the body's
(tracking.py rule 6: "azimuth-only rotors follow the azimuth") or the QSO partner's great-circle
bearing. The box turns its elevation to that number. The sun at azimuth 65, elevation 22 from
the station: the dish was raised to 65 and the status said ``tracking``; JA1ABC in PM95 heard
(bearing 42 from Berlin): the dish was raised to 42, following said the bearing, nothing said
anywhere. An EME station with its azimuth and elevation rotors as two rotators (each its own
topics) sends ``R/track moon`` to both. A group keeps such a box out ("a group's bearing would
tilt it", docs/groups.md); tracking and following do not."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from bridge.sky import Body, Sky
from tests.engine.test_follow import STATION
from tests.engine.virtual import VirtualRotator
from tests.support.sky import sun_altaz

WALL = 1_781_000_000.0  # 2026-06-09 10:13 UTC: a fixed sky
SPOT = (0.0, -40.0)  # where the sun stands at about azimuth 65, elevation 22 then
START_EL = 10.0


def test_tracking_never_turns_an_elevation_rotor_to_the_bodys_azimuth() -> None:
    sun_az, sun_el = sun_altaz(*SPOT, WALL)
    assert abs(sun_az - sun_el) > 30.0  # (the two are far apart: the test can tell them)
    emulator = {"start_el_deg": START_EL}
    with VirtualRotator("prosistel-el", sky=Sky(*SPOT), wall_epoch_s=WALL, emulator=emulator) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.sun())
        v.run_for(120.0)  # (the sun moves little in two minutes: not a deadline)
        el = v.truth().el_deg
        assert el is not None
        # refused (left where it was) or following the sun's elevation: observed at 65
        assert abs(el - START_EL) <= 1.0 or abs(el - sun_el) <= 3.0, (el, sun_az, sun_el)
        # refused, and said so (feature_commands.py rule 6): nothing tracked
        [refused] = v.errors(ErrorKind.REFUSED)
        assert "elevation" in refused.message and "azimuth" in refused.message, refused
        assert v.status.tracking is None and abs(el - START_EL) <= 1.0


def test_following_never_turns_an_elevation_rotor_to_a_bearing() -> None:
    emulator = {"start_el_deg": START_EL}
    with VirtualRotator("prosistel-el", follow=STATION, emulator=emulator) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.follow(True)
        v.heard("JA1ABC", "PM95")  # 42 degrees from the station
        v.run_for(60.0)  # (a turn of 32 degrees at 3 a second is 11 s: not a deadline)
        el = v.truth().el_deg
        assert el is not None and abs(el - START_EL) <= 1.0, el  # observed: 42
        # refused, and said so (feature_commands.py rule 6): nothing followed
        [refused] = v.errors(ErrorKind.REFUSED)
        assert "elevation" in refused.message and "azimuth" in refused.message, refused
        assert v.status.following is None
