"""Attack 28: a target just past a limit (``360.00001``, a script's float) is
refused, rightly, but the refusal rounds the number it quotes to six digits and contradicts
itself: ``azimuth 360 outside 0..360`` on R/error. The user
reads that 360 was refused on a rotor that takes 0..360. Real mosquitto, the Rotor-EZ emulator
on a real pty; asserted: the refusal's message."""

from __future__ import annotations

from tests.support.rig import Rig


def test_a_refusal_past_a_limit_does_not_quote_a_number_inside_it(rig: Rig) -> None:
    rig.add("tower", "rotorez")
    rig.start()
    rig.ready("tower")
    message = rig.refused("tower", "360.00001")
    assert "azimuth 360 outside 0..360" not in message, message
