"""Review 105: a garbled first reading is still confirmed by the true one that comes after it,
taken for the bearing, and a nudge from it turns the rotor the wrong way.

controller.py rule 9 (``_doubts_first``) believes a connection's first reading once a later one
agrees within ``doubt_deg`` plus what the rotor can turn between the two at its top speed
(motion.py ``top_speed_deg_s``: three times nominal, 18 deg/s on the 6 deg/s models), and takes
the earlier of the two. Commit 20e7d721 ended review 103's triple fault by asking the readings
that go on disagreeing at the moving rate, "the true reading no longer comes 8.4 s after the
garble"; but the time between two first answers is not the poll's alone:

- an M2 RC2800 az/el asks its two axes 200 ms apart (``axis_gap_s``): its second first answer
  comes 0.4 s after the first, and the allowance is 5 + 18 x 0.4 = 12.2 degrees. One flipped
  bit in the first azimuth line (``A P= 150.0`` read ``A P= 140.0``, the ``5`` 0x35 read as ``4``
  0x34) is confirmed by the clean answer after it, with no other fault: the rotator comes online
  at 140 with the rotor at 150, then is "moving" to 150, stopped, and R/error says the rotor
  turned with no command from the bridge; a nudge of +5 (``nudge_step_deg`` 5, the console's
  arrows) made in that window is judged from 140 and turns the rotor down from 150 to 145;
- a GS-232B whose first answer is flipped (``AZ=150`` read ``AZ=110``) and whose next is lost
  on the line is asked again at the next poll, after the reply timeout and on the idle grid,
  2.0 s later: the allowance is 5 + 18 x 2.0 = 41 degrees, the true 150 "agrees" with 110 and
  110 is taken; a nudge of +10 (Home Assistant's button) turns the rotor from 150 down to 120;
- with no reply lost, the moving rate itself opens the window: a GS-232B's true first answer,
  then two flipped ones (``AZ=158``, ``AZ=050``) make three that disagree, the fourth is asked
  at the moving rate, 0.2 s on, and compared with the one two back (5 + 18 x 0.25 = 9.5
  degrees): the true 150 "agrees" with 158 and 158 is taken, the true first answer being out
  of the window; a nudge of -5 turns the rotor up from 150 to 153;
- a K3NG box in GS-232B mode built with OPTION_DELAY_C_CMD_OUTPUT answers ``C`` 400 ms late
  (protocols/gs232.py): its two first answers are 0.42 s apart, the allowance 12.6 degrees,
  and one flipped bit (150 read 140) is confirmed by the clean answer after it, no other
  fault: a nudge of +5 turns the rotor down to 145.

Now two first readings agree within ``doubt_deg`` alone (the first of them taken); further
apart they are a turn only on FIRST_TURN_READINGS on one line.

In virtual time: the emulated controller at rest at 150 (45 up on the RC2800); its first answer
reaches the host with one digit flipped (and, on the GS-232B, its second answer lost on the
line, or its second and third flipped); the rest as sent.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import pytest

from bridge.core.model import Source
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
WATCH_S = 60.0  # a nudge's turn of up to 30 degrees at 6 deg/s, with room (virtual time)
ONLINE_S = 20.0  # a few answers and a poll or two (virtual time)
K3NG_LATE_S = 0.4  # K3NG's OPTION_DELAY_C_CMD_OUTPUT (protocols/gs232.py), a lag, not a wait


def lines_as(plan: list[tuple[bytes, bytes | None]], end: bytes) -> Callable[[bytes, float], bytes]:
    """The controller's output reaches the host line by line (each whole line, to its ``end``,
    at its last byte, as a reply is read); the first lines that hold the next ``(old, new)`` of
    ``plan`` have ``old`` replaced by ``new``, or are lost on the line where ``new`` is None;
    then as sent."""
    buf = bytearray()
    todo = list(plan)

    def line_fault(data: bytes, now: float) -> bytes:
        buf.extend(data)
        out = b""
        while end in buf:
            cut = buf.index(end) + 1
            line = bytes(buf[:cut])
            del buf[:cut]
            if todo and todo[0][0] in line:
                old, new = todo.pop(0)
                if new is None:
                    continue
                line = line.replace(old, new, 1)
            out += line
        return out

    return line_fault


def nudged(v: VirtualRotator, nudge_deg: float) -> tuple[float | None, float, float]:
    """Start the bridge, nudge from the first bearing shown, watch the rotor: the bearing the
    nudge was made from, and the lowest and highest the rotor went."""
    v.link_up()
    v.run_until(lambda h: h.status.available, ONLINE_S, "the controller answers")
    shown = v.status.bearing_deg
    v.aim(replace(v.cfg.aim.nudge(v.status, nudge_deg, None), source=Source.MQTT))
    lowest = highest = v.truth().az_deg
    t = v.now
    while v.now < t + WATCH_S:
        v.run_for(1.0)  # (a step of virtual time: not a deadline)
        lowest, highest = min(lowest, v.truth().az_deg), max(highest, v.truth().az_deg)
    return shown, lowest, highest


def test_rc2800_one_flipped_first_answer_is_not_the_bearing_a_nudge_is_made_from(
    rig: Rig,
) -> None:
    v = rig("rc2800", emulator={"start_az_deg": REST_DEG, "start_el_deg": 45.0}, connect=False)
    v.to_host = lines_as([(b"P= 150.0", b"P= 140.0")], b"\r")
    shown, lowest, highest = nudged(v, 5.0)
    assert lowest >= REST_DEG - 1.0, (
        f"a nudge of +5 at {REST_DEG:g} (shown {shown}) turned the rotor down to {lowest:g}"
    )
    assert v.truth().az_deg == pytest.approx(REST_DEG + 5.0, abs=1.0)


def test_rc2800_one_flipped_first_answer_is_never_shown_nor_a_turn_stopped(rig: Rig) -> None:
    v = rig("rc2800", emulator={"start_az_deg": REST_DEG, "start_el_deg": 45.0}, connect=False)
    v.to_host = lines_as([(b"P= 150.0", b"P= 140.0")], b"\r")
    v.link_up()
    v.run_for(WATCH_S)
    shown = {s.bearing_deg for s in v.published() if s.available} - {None}
    assert shown == {REST_DEG}, shown
    said = [e.message for e in v.errors()]
    assert not [m for m in said if "no command" in m], said


def test_gs232b_a_flipped_first_answer_and_a_lost_one_are_not_the_bearing_a_nudge_is_made_from(
    rig: Rig,
) -> None:
    v = rig("gs232b-az", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = lines_as([(b"AZ=150", b"AZ=110"), (b"AZ=150", None)], b"\n")
    shown, lowest, highest = nudged(v, 10.0)
    assert lowest >= REST_DEG - 1.0, (
        f"a nudge of +10 at {REST_DEG:g} (shown {shown}) turned the rotor down to {lowest:g}"
    )
    assert v.truth().az_deg == pytest.approx(REST_DEG + 10.0, abs=1.0)


def test_gs232b_two_flipped_first_answers_after_a_true_one_are_not_the_bearing_a_nudge_is_made_from(
    rig: Rig,
) -> None:
    v = rig("gs232b-az", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = lines_as(
        [(b"AZ=150", b"AZ=150"), (b"AZ=150", b"AZ=158"), (b"AZ=150", b"AZ=050")], b"\n"
    )
    shown, lowest, highest = nudged(v, -5.0)
    assert highest <= REST_DEG + 1.0, (
        f"a nudge of -5 at {REST_DEG:g} (shown {shown}) turned the rotor up to {highest:g}"
    )
    assert v.truth().az_deg == pytest.approx(REST_DEG - 5.0, abs=1.0)


def test_gs232b_answering_late_one_flipped_first_answer_is_not_the_bearing_a_nudge_is_made_from(
    rig: Rig,
) -> None:
    v = rig("gs232b-az", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.answer_after(K3NG_LATE_S)
    v.to_host = lines_as([(b"AZ=150", b"AZ=140")], b"\n")
    shown, lowest, highest = nudged(v, 5.0)
    assert lowest >= REST_DEG - 1.0, (
        f"a nudge of +5 at {REST_DEG:g} (shown {shown}) turned the rotor down to {lowest:g}"
    )
    assert v.truth().az_deg == pytest.approx(REST_DEG + 5.0, abs=1.0)
