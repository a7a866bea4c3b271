"""A Yaesu GS-232A/B in virtual time: bearings straight out, stops at once, the 450-degree
overlap, K3NG's blank lines, a refused bearing, a glitched reply, a satellite pass.

The box takes a new bearing at any time (no brake on Yaesu rotors), answers every command (a CR
where it returns nothing) and reads its potentiometer in whole degrees. 9600 baud: one poll
(``C2`` and ``AZ=123  EL=045`` CR LF) takes 20 ms of the line.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import pytest

from bridge.core.model import ErrorKind, MotionState, SetOption, Target
from bridge.emulators.gs232 import Outcome
from bridge.session import motion as mo
from tests.engine.test_session_passed import flicker_el
from tests.engine.test_session_tracking import BERLIN, a_pass_that, fly
from tests.engine.virtual import VirtualRotator, moves, settled_at

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}


def ready(rig: Rig, model: str = "gs232b", **emulator: object) -> VirtualRotator:
    v = rig(model, emulator={**FAST, **emulator})
    v.run_until_state(IDLE, 30)
    return v


@pytest.mark.parametrize("model", ["gs232a", "gs232b"])
def test_a_target_arrives_and_the_bearing_is_read_back(rig: Rig, model: str) -> None:
    v = ready(rig, model, start_az_deg=10, start_el_deg=5)
    v.target(123.4, 45.6)
    v.run_until(settled_at(123, 46), 60, "at 123/46")
    assert moves(v) == [b"W123 046"]
    assert (v.status.bearing_deg, v.status.elevation_deg) == (123.0, 46.0)
    assert v.errors() == []


def test_a_stop_while_turning_goes_out_at_once_and_takes(rig: Rig) -> None:
    v = ready(rig)
    v.target(300, 60)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 30, 30, "turning")
    t, before = v.now, len(v.writes)  # (a poll may have gone out at this instant, before it)
    v.stop()
    assert [(w.t, w.data) for w in v.writes[before:]][:1] == [(t, b"S\r")]  # the same instant
    v.run_until(lambda h: h.state is IDLE, 10, "idle")
    truth = v.truth()
    assert not truth.is_moving and 30 < truth.az_deg < 40
    assert v.status.bearing_deg == round(truth.az_deg)
    assert v.sent(since=t).count(b"S\r") == 1 and v.errors() == []


def test_a_new_target_while_turning_goes_straight_out_without_a_stop(rig: Rig) -> None:
    v = ready(rig)
    v.target(200, 40)
    v.run_until(lambda h: h.truth().az_deg > 50, 30, "turning")
    t = v.now
    v.target(20, 10)
    v.run_until(lambda h: moves(h, t), 2, "the new bearing")
    assert v.truth().is_moving and moves(v, t) == [b"W020 010"]
    v.run_until(settled_at(20, 10), 120, "at 20/10")
    assert b"S\r" not in v.sent()


def test_k3ng_blank_lines_after_w_are_no_error(rig: Rig) -> None:
    v = ready(rig, blank_lines_after_w=2)
    for az in (100, 50, 150):
        v.target(az, 20)
        v.run_until(settled_at(az, 20), 60, f"at {az}")
    assert v.errors() == []


def test_the_450_degree_rotor_turns_on_through_north_into_its_overlap(rig: Rig) -> None:
    v = ready(rig, "gs232b-az-450", start_az_deg=350)
    v.aim(Target(20))  # a true bearing, judged: 30 degrees on, not 330 back
    v.run_until(settled_at(380), 60, "at 380")
    assert moves(v) == [b"M380"]
    assert (v.status.bearing_deg, v.status.raw_bearing_deg, v.status.overlap) == (20, 380, "cw")


@pytest.mark.parametrize("model", ["gs232a-450", "gs232b-450"])
def test_an_az_el_box_at_450_degrees_keeps_its_overlap(rig: Rig, model: str) -> None:
    """A G-5500 with its box at P45: from 400 (40 degrees on the overlap), 45 is 5 degrees on,
    not a swing of 355 degrees back through the whole circle."""
    v = ready(rig, model, start_az_deg=400, start_el_deg=5)
    v.aim(Target(45, 10))
    v.run_until(settled_at(405, 10), 60, "at 405/10")
    assert moves(v) == [b"W405 010"]
    assert (v.status.bearing_deg, v.status.raw_bearing_deg, v.status.overlap) == (45, 405, "cw")


def test_k3ng_answering_late_for_ham_radio_deluxe_is_not_offline(rig: Rig) -> None:
    """K3NG's OPTION_DELAY_C_CMD_OUTPUT answers C2 400 ms late."""
    v = ready(rig, processing_delay_s=0.45, start_az_deg=10, start_el_deg=5)
    v.target(40, 10)
    v.run_until(settled_at(40, 10), 60, "at 40/10")
    assert v.errors() == []


def test_k3ng_reads_a_little_below_the_horizon_as_the_horizon(rig: Rig) -> None:
    """K3NG prints an elevation of -1 (its pot a degree off at the horizon) as EL=00-1: the
    rotator stays online and reads elevation 0."""
    v = ready(rig, start_az_deg=10, start_el_deg=0)
    below: list[float] = []
    seen = bytearray()  # what the box sent so far (the line hands it over a byte at a time)

    def drifted(data: bytes, now: float) -> bytes:
        out = bytearray()
        for byte in data:
            seen.append(byte)
            if seen.endswith(b"EL=000"):
                below.append(now)
                out += b"-1"  # EL=00 went out already
            else:
                out.append(byte)
        return bytes(out)

    v.to_host = drifted
    t = v.now
    v.run_for(10)
    assert len(below) > 5 and v.errors(since=t) == []
    assert (v.state, v.status.bearing_deg, v.status.elevation_deg) == (IDLE, 10, 0)


def test_a_bearing_the_box_refuses_is_reported_and_nothing_moves(rig: Rig) -> None:
    v = ready(rig, "gs232b-az-450", start_az_deg=77)
    v.device.receive(b"P36\r", v.now)  # the box set to 360 degrees; the bridge told 450
    t = v.now
    v.aim(Target(400))  # past 360: on the controller's own scale
    v.run_until(lambda h: h.errors("refused", since=t), 1, "the refusal")
    refusal = v.errors("refused", since=t)[0]
    assert "the controller refused the target" in refusal.message
    assert v.frames(Outcome.REFUSED)[-1].data == b"M400"
    v.run_until(lambda h: h.state is IDLE, 1, "at rest at once, not a stall 10 s later")
    v.run_for(30)  # a quiet period, not a deadline: no stall is reported for it afterwards
    assert [e.kind for e in v.errors(since=t)] == ["refused"]
    assert v.truth().az_deg == 77 and not v.truth().is_moving
    assert {s.bearing_deg for s in v.published()} - {None} == {77.0}
    v.aim(Target(120))  # the next bearing goes out and is taken as always
    v.run_until(settled_at(120), 60, "at 120")


@pytest.mark.parametrize("lead_s", [0.001, 0.004, 0.008])
def test_a_bearing_refused_just_before_a_poll_is_still_the_targets_refusal(
    rig: Rig, lead_s: float
) -> None:
    """link.py rule 4: a bearing the box refuses, given a few ms before a poll is due. The
    poll waits until the refusal can have come (``M400`` CR and ``?>`` CR at 9600 baud, a
    byte time to turn round): the refusal answers the target, reported as such, at rest at
    once. Before, ``C`` went out first and the ``?>`` after it was taken for junk: a protocol
    error, then a stall 2.5 s later."""
    v = ready(rig, "gs232b-az-450", start_az_deg=77)
    v.device.receive(b"P36\r", v.now)  # the box set to 360 degrees; the bridge told 450

    def polls() -> list[float]:
        return [w.t for w in v.writes if w.data == b"C\r"]

    seen = len(polls())
    v.run_until(lambda h: len(polls()) >= seen + 2, 30, "two polls at rest")
    last, before = polls()[-1], polls()[-2]
    v.run_for(last + (last - before) - lead_s - v.now)  # just before the next
    t = v.now
    v.aim(Target(400))
    v.run_for(5)  # a quiet period, not a deadline
    assert [e.kind for e in v.errors(since=t)] == ["refused"]
    assert v.state is IDLE and not v.truth().is_moving
    writes = [w for w in v.writes if w.t >= t]
    # refused, sent again once (controller.py rule 11: a flipped bit makes such a frame),
    # refused again: reported; nothing between a bearing and its refusal
    assert [w.data for w in writes[:3]] == [b"M400\r", b"M400\r", b"C\r"]
    assert writes[1].t - writes[0].t >= (5 + 3) * 10 / 9600  # once its refusal came
    assert writes[2].t - writes[1].t >= (5 + 3 + 1) * 10 / 9600  # M400 CR, ?> CR, a byte


def test_a_new_bearing_refused_while_turning_stops_the_rotor(rig: Rig) -> None:
    """The box refuses a new bearing mid-turn and keeps turning to the one before, which
    nobody wants any more: the bridge reports the refusal and stops the rotor."""
    v = ready(rig, "gs232b-az-450", start_az_deg=77)
    v.device.receive(b"P36\r", v.now)  # the box set to 360 degrees; the bridge told 450
    v.aim(Target(300))
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 100, 60, "turning")
    t = v.now
    v.aim(Target(400))  # past 360: the box refuses it and turns on to 300
    v.run_until(lambda h: h.errors("refused", since=t), 1, "the refusal")
    assert "stopped" in v.errors("refused", since=t)[0].message
    assert v.sent(since=t).count(b"S\r") >= 1
    v.run_until(lambda h: h.state is IDLE, 30, "at rest")
    assert 100 < v.truth().az_deg < 200 and not v.truth().is_moving


def test_a_refusal_after_a_setting_is_not_the_targets(rig: Rig) -> None:
    """A ``?>`` that follows a setting written after the target refuses the setting, not the
    target: the rotor still turns there."""
    v = ready(rig, start_az_deg=10, start_el_deg=0)
    v.garble_writes(b"X4\r", b"X9\r")  # the box gets a speed it refuses: ?>
    t = v.now
    v.command(Target(200, 0))
    v.run_until(lambda h: b"W200 000\r" in h.sent(since=t), 2, "the target written")
    v.command(SetOption("speed", "4"))
    v.run_until(lambda h: h.frames(Outcome.REFUSED, since=t), 2, "the setting refused")
    assert [f.data for f in v.frames(since=t)][:2] == [b"W200 000", b"X9"]
    v.run_until(settled_at(200, 0), 120, "at 200 all the same")
    assert v.errors("refused", since=t) == []


def test_a_setting_set_with_a_target_goes_first_and_its_refusal_is_not_the_targets(
    rig: Rig,
) -> None:
    """A speed set together with a target is written ahead of it (the turn starts at the
    speed set); the box's ``?>`` to it refuses the setting, and the target goes all the same."""
    v = ready(rig, start_az_deg=10, start_el_deg=0)
    v.garble_writes(b"X4\r", b"X9\r")
    t = v.now
    v.command(Target(200, 0), SetOption("speed", "4"))
    v.run_until(lambda h: h.frames(Outcome.REFUSED, since=t), 2, "the setting refused")
    v.run_until(settled_at(200, 0), 120, "at 200 all the same")
    assert [f.data for f in v.frames(since=t) if f.data != b"C2"][:2] == [b"X9", b"W200 000"]
    assert v.errors("refused", since=t) == []


def test_a_glitched_reply_before_the_real_one_is_no_reading(rig: Rig) -> None:
    v = ready(rig, start_az_deg=100, start_el_deg=20)
    v.run_for(10)
    glitched = v.glitch_once(b"A", b"\xffAZ=359  EL=000\r\n")
    t = v.now
    v.run_for(30)
    assert glitched
    assert {(s.bearing_deg, s.elevation_deg) for s in v.published(since=t)} <= {(100.0, 20.0)}
    assert v.state is IDLE


def test_a_satellite_pass_is_followed_within_3_degrees() -> None:
    """A G-5500 on a GS-232B (6 and 3 deg/s here) follows a pass clear of north (a 360-degree
    azimuth cannot cross it without a turn round) as closely as the SPIDs do (3 degrees):
    whole degrees on the wire, whole degrees read back."""
    tle = a_pass_that(across_north=False)
    v, errors = fly("gs232b", tle)
    with v:
        worst_az = max(e[1] for e in errors[5:])  # the body rises at the horizon's edge
        worst_el = max(e[2] for e in errors[5:])
        assert worst_az <= 3.0 and worst_el <= 3.0, (worst_az, worst_el)
        assert not v.frames(Outcome.REFUSED)
    assert BERLIN  # the station the pass was computed for


def test_a_bare_azimuth_keeps_the_elevation(rig: Rig) -> None:
    v = ready(rig, start_az_deg=10, start_el_deg=30)
    v.target(100)  # no elevation named: the box must not be sent elevation 0
    v.run_until(settled_at(100, 30), 60, "at 100/30")
    assert moves(v) == [b"W100 030"]


def test_a_refusals_stop_lost_on_the_line_is_sent_again(rig: Rig) -> None:
    """stops.py rules 2 and 3 hold for the stop a refusal mid-turn asks for as for any other:
    its frame lost on the line, the rotor still seen turning, it is written again and the
    rotor stops far short of the bearing nobody wants any more (it was written once, and the
    rotor turned on to 300)."""
    v = ready(rig, "gs232b-az-450", start_az_deg=77)
    v.device.receive(b"P36\r", v.now)  # the box set to 360 degrees; the bridge told 450
    v.aim(Target(300))
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 100, 60, "turning")
    t = v.now
    v.drop_writes(b"S\r")  # the refusal's stop never reaches the box
    v.aim(Target(400))  # past 360: the box refuses it and turns on to 300
    v.run_until(lambda h: h.errors("refused", since=t), 1, "the refusal")
    v.run_until(lambda h: h.state is IDLE, 30, "at rest")
    assert v.sent(since=t).count(b"S\r") == 2
    assert 100 < v.truth().az_deg < 200 and not v.truth().is_moving


def test_a_pot_flickering_a_count_either_way_does_not_keep_a_stopped_rotor_turning(
    rig: Rig,
) -> None:
    """An ADC reading a pot flickers a count up and down: with noise_deg 1 the elevation's 11
    then 9 was two degrees of movement (a review: after a STOP, 16 stop frames, "still turning
    after 3 stop commands", and the state left at moving)."""
    v = rig("gs232b", emulator={"start_el_deg": 10})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 30, "online")
    flicker_el(v, [0, 1, 0, -1])
    v.target(300.0, 10.0)
    v.run_for(3)
    t = v.now
    v.stop()
    v.run_for(30)

    assert v.sent(since=t).count(b"S\r") == 1 and v.errors() == []
    assert v.state is MotionState.IDLE and not v.truth().is_moving


def slowed(rig: Rig, speed: str) -> VirtualRotator:
    v = rig("gs232b", emulator={"start_az_deg": 100, "start_el_deg": 10})
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.option("speed", speed)
    v.run_for(5)
    return v


@pytest.mark.parametrize(
    ("speed", "target"), [("1", (130.0, 10.0)), ("3", (100.0, 30.0))], ids=["az-X1", "el-X3"]
)
def test_a_gs232_at_a_slow_speed_is_not_called_at_rest_while_it_still_turns(
    rig: Rig, speed: str, target: tuple[float, float]
) -> None:
    """motion.py rule 2 (a review): at X1 the azimuth turns 1.5 degrees a second, and three
    whole degrees (noise_deg and a count) took longer than the settle time: called arrived at
    128.9 on the way to 130 (at X3 the elevation, at 27.4 on the way to 30)."""
    v = slowed(rig, speed)
    v.target(*target)
    v.run_until(lambda h: h.state is IDLE, 60, "idle")
    assert not v.truth().is_moving


def test_a_hand_at_the_panel_of_a_slowed_gs232_is_one_move(rig: Rig) -> None:
    v = slowed(rig, "1")
    t = v.now
    v.manual_rotate(130)
    v.run_for(30)
    states = [s.state for s in v.published(since=t)]
    assert [k for k, _ in itertools.groupby(states)] == [MOVING, IDLE]
    assert abs(v.truth().az_deg - 130) < 1 and not v.truth().is_moving


def test_a_bearing_garbled_into_one_the_box_refuses_is_sent_once_more(rig: Rig) -> None:
    """controller.py rule 11: one flipped bit (``2`` 0x32 read as ``:`` 0x3A) made ``M200`` a
    frame the box answers with its refusal; the bearing goes again and is taken, and nothing
    is reported (before: "the controller refused the target", and it was dropped)."""
    v = ready(rig, "gs232b-az", start_az_deg=77)
    t = v.now
    v.garble_writes(b"M200\r", b"M:00\r")
    v.aim(Target(200))
    v.run_until(settled_at(200), 90, "at 200")
    assert v.errors(since=t) == []
    assert [f.data for f in v.frames(since=t) if f.data.startswith(b"M")] == [b"M:00", b"M200"]


@pytest.mark.parametrize("stall_s", [3.0, 4.0])
def test_replies_lost_at_the_target_are_no_stall(rig: Rig, stall_s: float) -> None:
    """motion.py rule 3 (an attack pass): a rotor that came to its target, its replies lost
    from just after, waits for the reading that shows it still (rule 2); the stall check,
    which did not ask for an error beyond the tolerance, called it stalled at its target
    ("brake paddle pressed or rotor stuck") and stopped it, before the silence made the
    controller offline."""
    v = rig("gs232b", settings={"stall_timeout_s": stall_s})
    v.run_until_state(IDLE, 60)
    v.target(100)
    v.run_until(lambda h: not h.truth().is_moving and abs(h.truth().az_deg - 100) < 0.5, 60)
    v.run_for(0.5)  # (a reading or two at it: not yet still for settle_s)
    t0, motion = v.now, v.session.controller.motion
    assert motion.state is MOVING and mo.at_target(motion, v.cfg.motion)  # (not vacuous)
    v.set_silent(True)
    v.run_for(6)
    assert [e.kind for t, e in v.events if t >= t0] == [ErrorKind.SERIAL]  # offline, no stall
    assert "turn" not in v.events[-1][1].message  # (at its target: no turn under way)
    assert b"S\r" not in v.sent(since=t0)  # no stop


def test_replies_lost_across_a_stop_that_took_send_no_second_stop(rig: Rig) -> None:
    """motion.py ``stop_again`` (an attack pass): replies lost from 0.5 s before a stop to 1 s
    after it; the controller heard it and the rotor stopped at once. The first reading after
    the gap shows the way the rotor came before the stop, no turning since: a second stop
    went to the rotor at rest 2 s on."""
    v = rig("gs232a", emulator={"start_az_deg": 10})
    v.run_until_state(IDLE, 60)
    v.target(200)
    v.run_for(8)
    v.set_silent(True)
    v.run_for(0.5)
    t0 = v.now
    v.stop()
    v.run_for(1.0)
    v.set_silent(False)
    v.run_until_state(IDLE, 30)
    v.run_for(5)
    assert not v.truth().is_moving and v.truth().az_deg < 200
    assert [w.t - t0 for w in v.writes if w.t >= t0 and w.data == b"S\r"] == [0.0]


def test_a_target_garbled_into_a_jog_up_is_stopped_past_the_elevation_limit(rig: Rig) -> None:
    """motion.py rule 10 (an attack pass): a target frame is one flipped bit from a jog (``W``
    0x57, ``U`` 0x55: up until stopped; K3NG goes by the first letter alone). With the
    elevation held to 90 degrees, the rotor climbed through its target, 89, to 103 before a
    pass 10 degrees beyond it was told. It is stopped just past its limit now, and the error
    says which limit, and where the rotor is on both axes."""
    v = rig(
        "gs232b",
        emulator={**FAST, "start_az_deg": 100, "start_el_deg": 10},
        settings={"el_max_deg": 90},
    )
    v.run_until_state(IDLE, 30)
    t = v.now
    v.garble_writes(b"W100 089\r", b"U\r")
    v.target(100, 89)
    v.run_until(lambda h: b"S\r" in h.sent(since=t), 60, "a stop")
    v.run_until_state(IDLE, 10)
    truth = v.truth()
    assert not truth.is_moving and truth.el_deg is not None and truth.el_deg < 98, truth
    said = v.errors("stalled", since=t)
    assert len(said) == 1, said
    at = v.status.elevation_deg
    assert f"its elevation limit: {at:g}°, beyond el_max_deg 90°" in said[0].message, said[0]
    assert f"now at 100°, elevation {at:g}°" in said[0].message
    assert v.sent(since=t).count(b"S\r") == 1 and v.status.target_el_deg is None


@pytest.mark.parametrize("model", ["gs232b", "gs232a-az"])
def test_a_poll_answered_after_its_reply_time_around_a_stop_is_told_nowhere(
    rig: Rig, model: str
) -> None:
    """protocols/gs232.py rule 5: a loaded host had the answer of the poll written with a STOP
    after its reply time (1 s); the next poll took it, and that poll's own answer, a line
    later, was told on R/error as bytes that are no reply. The rotor still stops where it was,
    every reading is the box's, and the next target arrives."""
    settings = {"idle_poll_interval_s": 0.3, "moving_poll_interval_s": 0.1, "settle_s": 0.6}
    v = rig(
        model,
        settings={**settings, "stall_timeout_s": 2.5, "silence_timeout_s": 2.0},
        emulator={**FAST, "start_az_deg": 10},
    )
    v.run_until_state(IDLE, 30)
    v.target(300, 0)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 30, 30, "turning")
    poll = b"C\r" if model.endswith("-az") else b"C2\r"
    t = v.stopped_with_late_answers(poll, 1.2)  # past the reply time (1 s)
    truth = v.truth()
    assert not truth.is_moving and v.status.bearing_deg == round(truth.az_deg)
    v.target(90, 0)
    v.run_until(settled_at(90, None if model.endswith("-az") else 0), 60, "at 90")
    assert v.errors() == [] and all(s.available for s in v.published(since=t))


def test_a_setting_refused_with_a_new_target_mid_turn_neither_stops_nor_drops_the_target(
    rig: Rig,
) -> None:
    """BUG (reported, a cold review): a speed set together with a new target goes first, and
    the target went in the same step, so it was the last command written when the box's ``?>``
    to the setting came back: taken as the target's refusal, the rotor was stopped mid-turn
    and the new target dropped with a ``refused`` error. The target now waits until the
    setting's refusal can have come (link.py rule 4)."""
    v = ready(rig, start_az_deg=10, start_el_deg=0)
    v.garble_writes(b"X4\r", b"X9\r")  # the box gets a speed it refuses: ?>
    v.target(300, 0)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 60, 60, "turning")
    t = v.now
    v.command(Target(200, 0), SetOption("speed", "4"))
    v.run_until(lambda h: h.frames(Outcome.REFUSED, since=t), 2, "the setting refused")
    v.run_for(30)
    assert v.errors("refused", since=t) == []
    assert b"S\r" not in v.sent(since=t)
    v.run_until(settled_at(200, 0), 120, "at 200 all the same")
    assert [f.data for f in v.frames(since=t)].count(b"W200 000") == 1


def test_a_setting_refused_with_a_target_at_rest_sends_the_target_once(rig: Rig) -> None:
    """BUG (reported, a cold review): at rest, the setting's ``?>`` was taken as the target's
    refusal ("the target did not move the rotor, or was refused": sent once more)."""
    v = ready(rig, start_az_deg=10, start_el_deg=0)
    v.garble_writes(b"X4\r", b"X9\r")
    t = v.now
    v.command(Target(200, 0), SetOption("speed", "4"))
    v.run_until(settled_at(200, 0), 120, "at 200")
    assert [f.data for f in v.frames(since=t)].count(b"W200 000") == 1
