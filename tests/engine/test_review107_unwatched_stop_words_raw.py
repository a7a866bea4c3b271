"""Review 107: the unwatched stop's words name the controller's raw reading, not a true
bearing, beside a status and other stop words in true bearings.

controller.py rule 9's ``_unwatched_stop`` (commit 025ee699) says "N first readings in a row do
not agree (the last X)", X from ``_where(reply)``: the controller's raw value. With
``az_offset_deg`` set (pointing.py: the rotor's scale turned against true north) every other
bearing the user reads is true: R/status's ``bearing_deg``, and rule 10's stop words for a turn
nobody asked for ("from 250° to 256.1°", "in true bearings"). The unwatched stop's "the last
210/0" is 100 degrees off the bearing that answer would show (310). (The doubt's own words, "N
first readings in a row disagree, the last ...", are raw too, as before these commits.)

In virtual time: the emulated Easycomm II box at rest at raw 150 (true 250 with
``az_offset_deg`` 100); every position answer off by 0, +60 or -60 degrees in turn (review
100's line), the eighth reading raw 210.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from tests.engine.garblers import every_answer_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
RAW_REST_DEG = 150.0
OFFSET_DEG = 100.0
OFFSETS = [0.0, 60.0, -60.0]
GARBLED_S = 3.0  # the first unwatched stop and its words (virtual time)
EIGHTH_TRUE = "310"  # the eighth answer, raw 150 + 60, in true bearings


def test_the_unwatched_stop_names_the_last_reading_in_true_bearings(rig: Rig) -> None:
    v = rig(
        "easycomm2",
        emulator={"start_az_deg": RAW_REST_DEG},
        settings={"az_offset_deg": OFFSET_DEG},
        connect=False,
    )
    v.to_host = every_answer_off(OFFSETS)
    v.link_up()
    v.run_for(GARBLED_S)
    said = [e.message for e in v.errors() if e.kind == ErrorKind.STOP]
    assert said and "do not agree" in said[0], said
    assert f"(the last {EIGHTH_TRUE}" in said[0], said[0]
