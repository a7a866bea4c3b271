"""Review 54 (cold review of 20f99924, motion.py rule 4): a turn the first readings of a bridge
just started find is ``carried`` "until the rotor is seen at rest or settled"; but ``carried``
is set at the first reading and cleared only at the end of the start-up brake window (BRAKING
to IDLE, ``brake_delay_s`` after the first reading: 5 s on a Rotor-EZ), not when readings show
the rotor still. A hand at the panel that begins in that window, after a second and more of
readings showing the rotor at rest (still by rule 2), is a turn the bridge saw begin from rest
with the link up: a hand, as parts.py rule 8 has it. It is taken for the turn a restart found:
``track sun`` then stops it and turns the antenna to the sun (review 52's finding, in the
first seconds after a start; the same on a brakeless MD-01 within its 1.5 s settle).
What a user notices: the beam he began turning at the panel as the bridge came up (a restart
by systemd, a reboot) is stopped and turned away from him by a tracking start (an automation
that starts tracking when the bridge comes back)."""

from __future__ import annotations

from bridge.sky import Body
from tests.engine.test_review52_hand_before_track_start import beside_the_sun
from tests.engine.test_session_tracking import off_deg


def test_a_hand_begun_at_rest_in_the_start_up_brake_window_ends_a_tracking_start() -> None:
    with beside_the_sun(settled=False) as (v, _sun_az, away, _toward):
        v.run_for(3.0)  # read at rest for 3 s (settle_s is 1.5): inside the 5 s brake window
        assert not v.status.moving and not v.truth().is_moving
        v.manual_rotate(round(away))  # a hand at the panel
        v.run_until(lambda h: h.status.moving, 10, "the bridge sees the hand's turn")
        hand = v.now
        v.track(Body.sun())
        v.run_until(lambda h: not h.truth().is_moving, 90, "the rotor at rest")
        v.run_for(30.0)
        sent = {f.outcome for f in v.frames(since=hand)}
        assert sent == {"query"}, sent  # polls only; observed: a stop, and the sun's bearing
        assert off_deg(v.truth().az_deg, round(away)) <= 1.0  # observed: 120 degrees off
        assert v.status.tracking is None and v.status.tracking_ended == "turned by hand"
