"""Attack 20: a press that says no, spelled as a real client sends it. ``R/park`` takes any
word but one that says no (interfaces/mqtt/payloads.py ``parse_press``: OFF, 0, false, no,
null...), and every other command topic reads its payload stripped of its blanks and refuses
what is not the word. An Arduino sketch that publishes ``strlen + 1`` bytes sends ``OFF`` with
its C string's NUL, and a Windows script writing UTF-8 sends a byte-order mark before it: the
lock refuses ``ON\\0`` and ``\\ufeffON`` as no switch word, but R/park takes ``OFF\\0`` and
``\\ufeffOFF`` as a press and turns the rotor to its park position. Real mosquitto, the
Rotor-EZ emulator on a real pty; what is asserted is what the user sees: the frames the
controller received and R/error."""

from __future__ import annotations

import json
import time
from typing import Any

from bridge.emulators.pty import EmulatedPort
from tests.integration.test_pointing_bridge import QUICK_BRIDGE, QUICK_EMU, motion_frames
from tests.support.rig import Rig

# a switch turned off, as C and Windows clients spell it: each says no
SAYS_NO = (b"OFF\x00", b"\xef\xbb\xbfOFF", b"\xef\xbb\xbffalse", b"0\x00")


def test_a_park_that_says_no_with_a_nul_or_a_bom_moves_nothing(rig: Rig) -> None:
    emu, t0, errors = park_words_judged(rig, SAYS_NO)
    parks = [e for e in errors if e.get("command", "").startswith("park")]
    assert len(parks) == len(SAYS_NO), f"a park that says no was taken as a press: {errors}"
    assert not motion_frames(emu, t0), "the rotor was sent to its park position"


def park_words_judged(
    rig: Rig, words: tuple[bytes, ...]
) -> tuple[EmulatedPort[Any], float, list[dict[str, Any]]]:
    """A Rotor-EZ at 120 with a park at 0, each of ``words`` published on ``R/park``; once the
    bridge has judged them all: its emulator, when they were sent, every R/error said."""
    emu = rig.add("tower", emu={**QUICK_EMU, "start_az_deg": 120}, park_az_deg=0, **QUICK_BRIDGE)
    rig.start()
    rig.ready("tower")
    t0 = time.monotonic()
    for payload in words:
        rig.probe.publish(rig.t("park"), payload)
    # a barrier on the same connection: the bridge takes its messages in order, so the park
    # words were judged before this refusal is said
    rig.probe.publish(rig.t("target"), "north")
    rig.probe.wait_for(rig.t("error"), lambda m: b"north" in m.payload, after=t0)
    errors = [json.loads(m.payload) for m in rig.probe.on(rig.t("error"))]
    return emu, t0, errors
