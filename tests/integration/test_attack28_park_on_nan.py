"""Attack 28: ``NaN`` on ``R/park`` parks the rotor. A press says no with any word that means
"no value" (``null``, ``none``, ``nil``, ``undefined``: interfaces/mqtt/payloads.py
``_NOT_A_PRESS``) and with a zero in any spelling, but ``NaN``, JavaScript's "no number" (a
Node-RED function node's ``Number(msg.payload)`` of a switch's ``"off"``, a dashboard's
``parseFloat`` of an empty field), is taken as a press, and so are ``Infinity`` and
``-Infinity``: the antenna turns to its park position on a value that is no number at all.
What cannot be read is never a yes (the house rule ``parse_press`` states); these are refused
on ``R/error`` and move nothing. Real mosquitto, the Rotor-EZ emulator on a real pty; asserted:
the frames the controller received and R/error."""

from __future__ import annotations

from tests.integration.test_attack20_park_says_no import park_words_judged
from tests.integration.test_pointing_bridge import motion_frames
from tests.support.rig import Rig

NO_NUMBER = (b"NaN", b"nan", b"Infinity", b"-Infinity")


def test_a_park_of_no_number_moves_nothing(rig: Rig) -> None:
    emu, t0, errors = park_words_judged(rig, NO_NUMBER)
    parks = [e for e in errors if e.get("command", "").startswith("park")]
    assert len(parks) == len(NO_NUMBER), f"a park of no number was taken as a press: {errors}"
    assert not motion_frames(emu, t0), "the rotor was sent to its park position"
