"""Review 99: on an RC2800 a well-formed glitch line right after the box's own line is taken
for the reading, where it was dropped.

link.py rule 9's guard ("a glitch ``;359`` just before the real ``;180`` is neither published
nor taken as a move") held both ways: a second reading in the quiet time spoiled the first,
and the controller was asked again. Commit 152a78a4 lets a box that streams whole lines
(``spec.streams_lines``, the RC2800) have the newer reading take the held one's place: a glitch
*before* the real line is overtaken by it (its own test), but a glitch *after* it, the newer,
is what is taken. Where no reading before doubts it (controller.py rule 9: the connection's
first), it is published: at connect ``A P= 100.0`` then a noise line ``A P= 359.0`` 0 ms
later showed the rotor at 359, and the next true reading was taken for a turn with no
command from the bridge, "from 359° to 100° ...: stopped; send the target again", a stop
written to a rotor at rest. Before the commit the glitch spoiled the exchange, the box was
asked again, and 100 was the first bearing shown, with no error.

In virtual time: the connection's first position line from the box is followed at once, in
the same read, by a well-formed glitch line; polled, and streaming.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.virtual import VirtualRotator

START_DEG = 100.0
GLITCH = b"A P= 359.0 S=9 ST\r"
WATCH_S = 30  # the connect, its first readings and what the bridge makes of them (virtual)


def glitch_after_first_line(v: VirtualRotator) -> list[float]:
    """``GLITCH`` reaches the host right behind the box's first position line, once; the list
    returned gets the instant it did."""
    when: list[float] = []
    line = bytearray()

    def after(data: bytes, now: float) -> bytes:
        if when:
            return data
        line.extend(data)
        if not data.endswith(b"\r"):
            return data
        whole = bytes(line).strip()
        line.clear()
        if not whole.startswith(b"A P"):
            return data
        when.append(now)
        return data + GLITCH

    v.to_host = after
    return when


@pytest.mark.parametrize("stream_s", [None, 0.5], ids=["asked", "streaming"])
def test_a_glitch_line_right_after_the_real_one_is_never_published(
    rig: Callable[..., VirtualRotator], stream_s: float | None
) -> None:
    v = rig("rc2800-az", emulator={"start_az_deg": START_DEG, "stream_s": stream_s}, connect=False)
    glitched = glitch_after_first_line(v)
    v.link_up()
    v.run_for(WATCH_S)
    assert glitched
    shown = {s.bearing_deg for s in v.published()} - {None}
    assert shown == {START_DEG}, shown
    assert not v.errors(), [e.message for e in v.errors()]
    assert v.status.available and v.status.bearing_deg == START_DEG


TARGET_DEG = 200.0
SETTLE_S = 10  # connected, at rest (virtual time, not a deadline)
GLITCH_FROM_DEG = 150.0  # the glitch follows the first line at or past this, mid-turn
AHEAD_DEG = 3.0  # the glitch says the rotor is this much further on (within its reach)
TURN_S = 60  # the turn to its end, with room (virtual time, not a deadline)


def test_a_glitch_line_right_after_the_real_one_mid_turn_is_never_published(
    rig: Callable[..., VirtualRotator],
) -> None:
    """The same mid-turn: a glitch within the rotor's reach (controller.py rule 9 lets it
    through) right behind a real line; before the commit the exchange was spoiled and asked
    again, and no bearing the box did not say was shown."""
    v = rig("rc2800-az", emulator={"start_az_deg": START_DEG})
    v.run_for(SETTLE_S)
    v.target(TARGET_DEG)
    real: list[float] = []
    line = bytearray()

    def after(data: bytes, now: float) -> bytes:
        if real:
            return data
        line.extend(data)
        if not data.endswith(b"\r"):
            return data
        whole = bytes(line).split()
        line.clear()
        if whole[:2] != [b"A", b"P="] or float(whole[2]) < GLITCH_FROM_DEG:
            return data
        real.append(float(whole[2]))
        return data + b"A P=%6.1f S=9 MV\r" % (real[0] + AHEAD_DEG)

    v.to_host = after
    t = v.now
    v.run_for(TURN_S)
    assert real
    glitch = round(real[0] + AHEAD_DEG, 1)
    assert glitch not in {s.bearing_deg for s in v.published(since=t)}, (real, glitch)
    assert v.truth().az_deg == TARGET_DEG and v.status.bearing_deg == TARGET_DEG
