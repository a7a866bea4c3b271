"""A Green Heron RT-21 in virtual time: bearings to the tenth straight out, a stop at once, a new
bearing while turning without a stop, junk and a glitched reply never read, a heading the box
drops reported as a stall, a satellite pass followed in azimuth.

The box takes a new heading at any time (it ramps and brakes by itself), answers only ``BI1;``
(``ddd.d;``) and reads its rotor in tenths. 4800 baud: one poll (``BI1;`` and ``123.4;``) takes
21 ms of the line.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from bridge.emulators.rt21 import Outcome
from bridge.sky import Body, Sky
from tests.engine.test_session_tracking import BERLIN, a_pass_that, off_deg
from tests.engine.virtual import VirtualRotator, moves, settled_at
from tests.support.sky import sgp4_altaz

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING
FAST = {"az_speed_deg_s": 6.0}


def ready(rig: Rig, **emulator: object) -> VirtualRotator:
    v = rig("rt21", emulator={**FAST, **emulator})
    v.run_until_state(IDLE, 30)
    return v


def test_a_target_arrives_to_the_tenth_and_is_read_back(rig: Rig) -> None:
    v = ready(rig, start_az_deg=10)
    v.target(123.46)
    v.run_until(settled_at(123.5), 60, "at 123.5")
    assert moves(v) == [b"AP1123.5\r;"]
    assert v.status.bearing_deg == 123.5
    assert v.errors() == []


def test_a_stop_while_turning_goes_out_at_once_and_takes(rig: Rig) -> None:
    v = ready(rig)
    v.target(300)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 30, 30, "turning")
    t = v.now
    v.stop()
    assert [w.t for w in v.writes if w.data == b";"] == [t]  # the same instant
    v.run_until(lambda h: h.state is IDLE, 10, "idle")
    truth = v.truth()
    assert not truth.is_moving and 30 < truth.az_deg < 40
    assert v.status.bearing_deg == round(truth.az_deg, 1)
    assert v.sent(since=t).count(b";") == 1 and v.errors() == []


def test_a_new_target_while_turning_goes_straight_out_without_a_stop(rig: Rig) -> None:
    v = ready(rig)
    v.target(200)
    v.run_until(lambda h: h.truth().az_deg > 50, 30, "turning")
    t = v.now
    v.target(20.2)
    v.run_until(lambda h: moves(h, t), 2, "the new bearing")
    assert v.truth().is_moving and moves(v, t) == [b"AP1020.2\r;"]
    v.run_until(settled_at(20.2), 120, "at 20.2")
    assert b";" not in v.sent() and v.frames(Outcome.STOP) == []


def test_a_padded_or_zero_filled_box_reads_the_same(rig: Rig) -> None:
    for padding in ("none", "zero"):
        v = ready(rig, start_az_deg=5.5, reply_padding=padding)
        assert v.status.bearing_deg == 5.5 and v.errors() == []
        v.target(7.1)
        v.run_until(settled_at(7.1), 30, "at 7.1")
        assert v.status.bearing_deg == 7.1


def test_a_glitched_reply_before_the_real_one_is_no_reading(rig: Rig) -> None:
    v = ready(rig, start_az_deg=100)
    v.run_for(10)
    glitched = v.glitch_once(b"1", b"\xff359.9;")
    t = v.now
    v.run_for(30)
    assert glitched
    assert {s.bearing_deg for s in v.published(since=t)} <= {100.0}
    assert v.state is IDLE


def test_a_digit_of_noise_between_polls_is_no_first_digit_of_the_next_reply(rig: Rig) -> None:
    """rt21.py rule 3: ``3`` left on an idle line, then the box's ``45.6;``, read as 345.6 (a
    reading 300 degrees off, published and taken as a move)."""
    v = ready(rig, start_az_deg=45.6)
    t = v.now
    v.run_for(0.3)  # between polls
    v._do(v.session.bytes_received(b"\xfe3", v.now))
    v.run_for(5)
    assert {s.bearing_deg for s in v.published(since=t)} - {None} <= {45.6}
    assert v.state is IDLE


def test_a_terminator_flipped_on_the_line_spoils_no_later_reply(rig: Rig) -> None:
    """rt21.py rule 3: one bit turns a reply's ``;`` into ``3``; that reply is lost, and the
    ``3`` it left must not begin the next one (``35.0`` for ``5.0``)."""
    v = ready(rig, start_az_deg=5.0, reply_padding="none")
    t, flipped = v.now, []

    def flip(data: bytes, now: float) -> bytes:
        if not flipped and b";" in data:
            flipped.append(now)
            return data.replace(b";", b"3", 1)
        return data

    v.to_host = flip
    v.run_for(8)
    assert flipped
    assert {s.bearing_deg for s in v.published(since=t)} - {None} <= {5.0}


def test_line_noise_is_reported_and_moves_nothing(rig: Rig) -> None:
    v = ready(rig, start_az_deg=77.7)
    t = v.now
    v.to_host = lambda data, now: b"#~" + data  # every reply arrives behind noise
    v.run_until(lambda h: h.errors("protocol", since=t), 30, "the error")
    assert v.frames(Outcome.MOVE) == [] and v.truth().az_deg == 77.7
    assert {s.bearing_deg for s in v.published(since=t)} - {None} <= {77.7}
    v.to_host = None
    v.target(80)
    v.run_until(settled_at(80), 30, "at 80 once the line is clean")


@pytest.mark.parametrize("lost", [1, 2])
def test_a_heading_the_box_drops_is_sent_once_more_then_a_stall(rig: Rig, lost: int) -> None:
    """The CR that runs a heading lost on the line: the box only stores it, and nothing moves.
    The same heading goes once more (controller.py rule 11) and the rotor turns; lost again,
    it is a stall, and nothing moved."""
    v = ready(rig, start_az_deg=77)
    t = v.now
    v.garble_writes(b"AP1150.0\r;", b"AP1150.0;", count=lost)  # only stored
    v.target(150)
    if lost == 1:
        v.run_until(lambda h: h.state is IDLE and h.truth().az_deg == 150, 60, "at 150")
        assert v.errors(since=t) == []
        return
    v.run_until(lambda h: h.errors("stalled", since=t), 60, "the stall")
    assert "stalled at 77" in v.errors("stalled", since=t)[0].message
    assert v.truth().az_deg == 77 and not v.truth().is_moving
    assert {s.bearing_deg for s in v.published(since=t)} - {None} == {77.0}


def test_a_satellite_pass_is_followed_in_azimuth_within_3_degrees() -> None:
    """An RT-21 on one rotor (6 deg/s) follows a pass clear of north (a 360-degree rotor cannot
    cross it without a turn round) in azimuth: tenths on the wire, tenths read back."""
    line1, line2, aos, los = a_pass_that(across_north=False)
    v = VirtualRotator(
        "rt21",
        sky=Sky(*BERLIN),
        wall_epoch_s=aos - 600.0,
        emulator={"az_speed_deg_s": 6.0},
        settings={"az_speed_deg_s": 6.0},
    )
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.satellite("TESTSAT", line1, line2))
        v.run_until(lambda h: h.wall() >= aos, 700, "AOS")
        errors: list[float] = []
        while v.wall() < los:
            v.run_for(1.0)
            sat_az, _ = sgp4_altaz(line1, line2, *BERLIN, v.wall())
            errors.append(off_deg(v.truth().az_deg, sat_az))
        worst = max(errors[5:])  # the body rises at the horizon's edge
        assert worst <= 3.0, worst
        assert len(moves(v)) >= 5 and not v.frames(Outcome.REFUSED)
        assert all(f.data.endswith(b"\r;") for f in v.frames(Outcome.MOVE))
