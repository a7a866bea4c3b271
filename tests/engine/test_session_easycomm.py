"""An Easycomm II/III controller in virtual time: bearings in tenths straight out, stops at once,
the controller that answers AZ and EL only when asked separately, a bearing it ignores, a
glitched reply, an alarm, a satellite pass.

The controller takes a new bearing at any time (no brake on the steppers of a SatNOGS rotator),
answers only questions, and reads its position in tenths. 19200 baud: one poll (``AZ EL`` and
``AZ123.4 EL45.0`` LF) takes about 11 ms of the line.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from bridge.emulators.easycomm import EasycommController, Outcome
from bridge.protocols.axes import Axis
from tests.engine.test_session_tracking import BERLIN, a_pass_that, fly
from tests.engine.virtual import Sent, VirtualRotator, moves, settled_at
from tests.engine.virtual_composite import VirtualComposite

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}


def ready(rig: Rig, model: str = "easycomm2", **emulator: object) -> VirtualRotator:
    v = rig(model, emulator={**FAST, **emulator})
    v.run_until_state(IDLE, 30)
    return v


@pytest.mark.parametrize("model", ["easycomm2", "easycomm3", "easycomm2-separate"])
def test_a_target_arrives_and_the_bearing_is_read_back(rig: Rig, model: str) -> None:
    v = ready(rig, model, start_az_deg=10, start_el_deg=5)
    v.target(123.44, 45.66)
    v.run_until(settled_at(123.4, 45.7), 60, "at 123.4/45.7")
    assert moves(v) == [b"AZ123.4", b"EL45.7"]
    assert (v.status.bearing_deg, v.status.elevation_deg) == (123.4, 45.7)
    assert v.errors() == [] and v.frames(Outcome.UNANSWERED) == []


def test_a_separate_controller_is_asked_each_axis_on_its_own_line(rig: Rig) -> None:
    v = ready(rig, "easycomm2-separate", start_az_deg=30, start_el_deg=20)
    v.run_for(5)
    polls = v.frames(Outcome.QUERY)
    assert polls and {f.data for f in polls} == {b"AZ", b"EL"}
    assert b"AZ EL\n" not in v.sent() and b"AZ\nEL\n" in v.sent()


def test_the_plain_model_on_separate_only_firmware_says_the_controller_does_not_answer(
    rig: Rig,
) -> None:
    """What docs/controllers.md tells users to look for before picking the -separate model."""
    v = rig("easycomm2")
    v.device = EasycommController("easycomm2-separate", now=v.now, **FAST)
    v.run_until(lambda h: h.errors("serial"), 30, "the complaint")
    assert "does not answer" in v.errors("serial")[0].message
    assert not v.status.available and {f.outcome for f in v.frames()} == {"unanswered"}


def test_a_stop_while_turning_goes_out_at_once_and_takes(rig: Rig) -> None:
    v = ready(rig)
    v.target(300, 60)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 30, 30, "turning")
    t = v.now
    v.stop()
    stops = [w.t for w in v.writes if w.t >= t and w.data == b"SA SE\n"]
    assert stops[:1] == [t]  # the same instant (after a poll that went out then, if one did)
    v.run_until(lambda h: h.state is IDLE, 10, "idle")
    truth = v.truth()
    assert not truth.is_moving and 30 < truth.az_deg < 40
    assert v.status.bearing_deg == pytest.approx(truth.az_deg, abs=0.051)
    assert v.sent(since=t).count(b"SA SE\n") == 1 and v.errors() == []


def test_a_new_target_while_turning_goes_straight_out_without_a_stop(rig: Rig) -> None:
    v = ready(rig)
    v.target(200, 40)
    v.run_until(lambda h: h.truth().az_deg > 50, 30, "turning")
    t = v.now
    v.target(20, 10)
    v.run_until(lambda h: moves(h, t), 2, "the new bearing")
    assert v.truth().is_moving and moves(v, t) == [b"AZ20.0", b"EL10.0"]
    v.run_until(settled_at(20, 10), 120, "at 20/10")
    assert b"SA SE\n" not in v.sent()


def test_a_bare_azimuth_keeps_the_elevation(rig: Rig) -> None:
    v = ready(rig, start_az_deg=10, start_el_deg=30)
    v.target(100)  # no elevation named: the controller must not be sent elevation 0
    v.run_until(settled_at(100, 30), 60, "at 100/30")
    assert moves(v) == [b"AZ100.0", b"EL30.0"]


def test_an_alarm_amid_the_answers_is_reported_and_leaves_the_reading_alone(rig: Rig) -> None:
    v = ready(rig, start_az_deg=100, start_el_deg=20)
    alarms: list[float] = []

    def alarm(data: bytes, now: float) -> bytes:
        if len(alarms) >= 3 or data != b"A":  # the first byte of a reply (the line is paced)
            return data
        alarms.append(now)
        return b"ALhoming\n" + data

    v.to_host = alarm
    t = v.now
    v.run_for(10)
    assert len(alarms) == 3 and {e.kind for e in v.errors(since=t)} == {"protocol"}
    readings = [s for s in v.published(since=t) if s.bearing_deg is not None]
    assert {(s.bearing_deg, s.elevation_deg) for s in readings} <= {(100.0, 20.0)}
    assert v.state is IDLE and v.status.available


def test_a_bearing_the_controller_ignores_is_reported_and_nothing_moves(rig: Rig) -> None:
    """A controller whose own limit is narrower than the bridge was told (here it never turns,
    as a SatNOGS controller with its azimuth limit at 0 would): the bridge sees no motion."""
    v = ready(rig, start_az_deg=77, start_el_deg=10)
    v.device.jam(v.now)
    t = v.now
    v.target(200, 10)
    v.run_until(lambda h: h.errors("stalled", since=t), 60, "the stall")
    assert "stalled at 77" in v.errors("stalled", since=t)[0].message
    assert {s.bearing_deg for s in v.published()} - {None} == {77.0}


def test_a_glitched_reply_before_the_real_one_is_no_reading(rig: Rig) -> None:
    v = ready(rig, start_az_deg=100, start_el_deg=20)
    v.run_for(10)
    glitched = v.glitch_once(b"A", b"\xffAZ359.0 EL0.0\n")
    t = v.now
    v.run_for(30)
    assert glitched
    assert {(s.bearing_deg, s.elevation_deg) for s in v.published(since=t)} <= {(100.0, 20.0)}
    assert v.state is IDLE


@pytest.mark.parametrize("model", ["easycomm2", "easycomm3-separate"])
def test_a_satellite_pass_is_followed_within_3_degrees(model: str) -> None:
    """A SatNOGS rotator (6 and 3 deg/s here) follows a pass clear of north (a 360-degree
    azimuth cannot cross it without a turn round) as closely as the SPIDs and the GS-232 do
    (3 degrees: the tracker's own step, not the wire's tenths)."""
    tle = a_pass_that(across_north=False)
    v, errors = fly(model, tle)
    with v:
        worst_az = max(e[1] for e in errors[5:])  # the body rises at the horizon's edge
        worst_el = max(e[2] for e in errors[5:])
        assert worst_az <= 3.0 and worst_el <= 3.0, (worst_az, worst_el)
        assert not v.frames(Outcome.REFUSED) and not v.frames(Outcome.UNANSWERED)
    assert BERLIN  # the station the pass was computed for


@pytest.mark.parametrize("jam_after_s", [0.0, 0.8])
def test_a_stall_stop_lost_is_followed_by_one_when_the_rotor_breaks_free_at_once(
    rig: Rig, jam_after_s: float
) -> None:
    """stops.py rule 4: the stall's stop lost on the line, the rotor breaks free as soon as
    the stall is said; the first reading that shows it turning brings one more stop, at once
    (an attack pass: with idle polls 5 s apart, a turn seen before ``stop_resend_s`` was let
    go, the rotor taken for stopped again, and it ran on to its old bearing)."""
    v = rig("easycomm2-az", settings={"idle_poll_interval_s": 5.0})
    v.run_until_state(IDLE, 30)
    v.target(200)
    v.run_until(lambda h: h.truth().az_deg >= 170, 60, "near 170")
    v.run_for(jam_after_s)
    v.jam()
    v.drop_writes(b"SA SE\n")
    v.run_until(lambda h: h.errors("stalled"), 60, "the stall")
    t = v.now
    v.unjam()
    v.run_for(10)
    stops = [w.t - t for w in v.writes if w.t > t and w.data == b"SA SE\n"]
    assert stops and stops[0] <= 1.0
    assert v.truth().az_deg < 195 and not v.truth().is_moving


# -- a turn nobody asked for (controller.py rule 10) ------------------------------------------
def unasked(v: VirtualRotator) -> list[str]:
    return [e.message for e in v.errors("stop") if "no command from the bridge" in e.message]


@pytest.mark.parametrize(
    "garbled",
    # E (0x45) read as M (0x4D): a jog; the space (0x20) read as 0 (0x30) would be AZ0EL, which
    # the emulator (and so this test) does not take for a move
    [b"AZ ML\n"],
    ids=["jog"],
)
def test_a_poll_a_flipped_bit_made_a_command_is_stopped_within_five_degrees(
    rig: Rig, garbled: bytes
) -> None:
    v = settled(ready(rig, start_az_deg=200, start_el_deg=20))
    t = v.now
    v.garble_writes(b"AZ EL\n", garbled)
    v.run_until(lambda h: unasked(h) != [], 10, "the turn seen and stopped")
    v.run_for(10)

    truth = v.truth()
    assert not truth.is_moving and 192 < truth.az_deg < 200 and truth.el_deg == 20
    assert v.state is IDLE and v.sent(since=t).count(b"SA SE\n") == 1
    [said] = unasked(v)
    assert said.startswith("the rotor turned with no command from the bridge, from 200°/20° to ")


def test_a_hand_at_the_panel_is_followed_where_the_user_says_so(rig: Rig) -> None:
    v = rig(
        "easycomm2", emulator={**FAST, "start_az_deg": 200}, settings={"unasked_moves": "follow"}
    )
    v.run_until_state(IDLE, 30)
    t = v.now
    v.manual_rotate(250)
    v.run_until(settled_at(250, 0), 30, "at 250")
    assert v.errors() == [] and b"SA SE\n" not in v.sent(since=t)


def settled(v: VirtualRotator) -> VirtualRotator:
    """Past the settle time after the connection's first reading (a turn seen from that one
    may have been under way: not judged, controller.py rule 10)."""
    v.run_for(v.cfg.motion.settle_s + 0.5)
    return v


def test_by_default_a_hand_at_the_panel_is_stopped_and_told_how_to_let_it_be(rig: Rig) -> None:
    v = settled(ready(rig, start_az_deg=200, start_el_deg=20))
    v.manual_rotate(250)
    v.run_until(lambda h: unasked(h) != [], 10, "the turn seen and stopped")
    v.run_for(5)
    assert not v.truth().is_moving and v.truth().az_deg < 210
    assert 'unasked_moves = "follow"' in unasked(v)[0]


def test_a_move_under_way_across_a_reconnect_is_not_taken_for_one_nobody_asked_for(
    rig: Rig,
) -> None:
    """A review: the connection's first reading mid-turn made the next a turn from rest."""
    v = ready(rig, start_az_deg=10, start_el_deg=5)
    v.target(200, 5)
    v.run_for(6)
    v.link_down("serial link to /dev/ttyVIRTUAL lost: unplugged")
    v.run_for(0.5)
    v.link_up()
    v.run_until(settled_at(200, 5), 90, "at 200/5")
    assert unasked(v) == []


def test_a_button_held_at_the_panel_is_stopped_four_times_at_most(rig: Rig) -> None:
    v = settled(ready(rig, start_az_deg=200, start_el_deg=20))
    t = v.now
    for _ in range(80):  # held for 40 s: the controller turns on after each stop
        v.manual_rotate(300)
        v.run_for(0.5)
    stops = [w for w in v.writes if w.t > t and w.data == b"SA SE\n"]
    assert 1 <= len(stops) <= 4 and len(unasked(v)) == 1
    assert any("stop it at the controller" in e.message for e in v.errors("stop"))


def test_with_slow_polls_at_rest_a_jog_is_still_stopped_within_a_few_degrees(rig: Rig) -> None:
    """A review: the garbled poll is answered in part, and the next came an idle poll later
    (10 s: the jog ran 60 degrees)."""
    v = rig(
        "easycomm2",
        emulator={**FAST, "start_az_deg": 200, "start_el_deg": 20},
        settings={"idle_poll_interval_s": 10.0},
    )
    v.run_until_state(IDLE, 60)
    v.run_for(3)
    v.garble_writes(b"AZ EL\n", b"AZ ML\n")
    v.run_until(lambda h: unasked(h) != [], 60, "the turn seen and stopped")
    v.run_for(10)
    assert not v.truth().is_moving and v.truth().az_deg > 190


def test_a_button_held_while_locked_is_fought_as_long_as_the_lock_holds(rig: Rig) -> None:
    """A review: the turn's bounded series let the lock's own stop go after four."""
    v = settled(ready(rig, start_az_deg=200, start_el_deg=20))
    v.lock(True)
    v.run_for(5)
    t = v.now
    for _ in range(80):  # held for 40 s
        v.manual_rotate(300)
        v.run_for(0.5)
    assert len([w for w in v.writes if w.t > t and w.data == b"SA SE\n"]) > 10


def test_an_operators_stop_lost_before_the_turn_is_judged_is_still_sent_until_it_takes(
    rig: Rig,
) -> None:
    v = settled(ready(rig, start_az_deg=200, start_el_deg=20))
    v.garble_writes(b"AZ EL\n", b"AZ ML\n")
    v.run_until(lambda h: h.state is MOVING, 10, "the jog seen")
    v.drop_writes(b"SA SE\n", count=6)
    v.stop()
    v.run_for(40)
    assert not v.truth().is_moving and v.truth().az_deg > 100


@pytest.mark.parametrize("model", ["easycomm2-az", "easycomm3-az"])
def test_an_azimuth_box_asks_as_the_az_el_ones_and_stops_a_turn_nobody_asked_for(
    rig: Rig, model: str
) -> None:
    """Its poll is ``AZ EL`` too (easycomm.py rule 8), one flipped bit from a jog: a turn from
    rest is stopped, and a user who turns it by hand says ``unasked_moves = "follow"``."""
    v = settled(ready(rig, model, start_az_deg=200))
    v.manual_rotate(250)
    v.run_until(lambda h: unasked(h) != [], 20, "the turn seen")
    v.run_until(lambda h: not h.truth().is_moving, 5, "stopped")
    assert v.truth().az_deg < 215
    follows = rig(
        model, settings={"unasked_moves": "follow"}, emulator={**FAST, "start_az_deg": 200}
    )
    follows.run_until_state(IDLE, 30)
    settled(follows)
    follows.manual_rotate(250)
    follows.run_until(lambda h: h.state is IDLE and abs(h.truth().az_deg - 250) < 0.1, 30, "at 250")
    assert follows.errors() == []


def test_an_elevation_turn_nobody_asked_for_is_told_with_its_elevation(rig: Rig) -> None:
    v = settled(ready(rig, start_az_deg=200, start_el_deg=20))
    v.device.manual_rotate(200, v.now, el_deg=60)  # type: ignore[call-arg]
    v.run_until(lambda h: unasked(h) != [], 20, "the turn seen and stopped")
    assert "turned with no command from the bridge, its elevation from 20° to 2" in unasked(v)[0]


def test_a_composites_elevation_box_tells_a_turn_by_its_elevation_alone() -> None:
    """A review: the box's own azimuth channel (87 here) is none of the antenna's (210)."""
    with VirtualComposite(
        "rotorez",
        "easycomm2",
        settings={"unasked_moves": "stop", "az_offset_deg": 10},
        emulators={
            Axis.ELEVATION: {"start_az_deg": 77, "start_el_deg": 20},
            Axis.AZIMUTH: {"start_az_deg": 200},
        },
    ) as v:
        v.run_until(
            lambda h: h.status.available and h.el.state is IDLE and h.az.state is IDLE, 30, "on"
        )
        v.run_for(10)
        v.el.device.manual_rotate(77, v.now, el_deg=60)  # type: ignore[call-arg]
        v.run_until(lambda h: unasked(h.el) != [], 30, "told")
        [said] = unasked(v.el)
        assert "turned with no command from the bridge, its elevation from 20° to 2" in said


def test_a_poll_garbled_into_a_jog_back_mid_turn_is_stopped_within_twenty_degrees(
    rig: Rig,
) -> None:
    """motion.py rule 5 on a wrapping scale: the turn to 300 became a jog left (``AZ ML``) at
    about 240; the rotor turned back, where it ran on to the end stop at 0 before."""
    v = settled(ready(rig, start_az_deg=200, start_el_deg=20))
    v.target(300, 20)
    v.run_until(lambda h: h.truth().az_deg > 240, 30, "on its way")
    t = v.now
    turned = v.truth().az_deg
    v.garble_writes(b"AZ EL\n", b"AZ ML\n")
    v.run_until(lambda h: h.errors("stalled", since=t) != [], 20, "the turn back told")
    v.run_for(10)
    truth = v.truth()
    assert not truth.is_moving and turned - 20 < truth.az_deg < turned + 5
    [said] = v.errors("stalled", since=t)
    assert "turned back" in said.message and "send the target again" in said.message
    assert v.state is IDLE and v.status.target_az_deg is None


def test_a_poll_garbled_into_a_jog_on_past_the_target_is_stopped_past_it(rig: Rig) -> None:
    """motion.py rule 5's pass: the turn to 100 became a jog left, the way it was going."""
    v = settled(ready(rig, start_az_deg=200, start_el_deg=20))
    v.target(100, 20)
    v.run_until(lambda h: h.truth().az_deg < 160, 30, "on its way")
    t = v.now
    v.garble_writes(b"AZ EL\n", b"AZ ML\n")
    v.run_until(lambda h: h.errors("stalled", since=t) != [], 40, "the pass told")
    v.run_for(10)
    truth = v.truth()
    assert not truth.is_moving and 80 < truth.az_deg < 100


def test_a_new_target_behind_a_turning_rotor_is_no_turn_back(rig: Rig) -> None:
    """The rotor turning towards 300 is sent 150: it coasts on a little, then turns back to the
    new target, which is what it was asked for."""
    v = settled(ready(rig, start_az_deg=200, start_el_deg=20))
    v.target(300, 20)
    v.run_until(lambda h: h.truth().az_deg > 240, 30, "on its way")
    t = v.now
    v.target(150, 20)
    v.run_until(settled_at(150, 20), 60, "at 150")
    assert v.errors(since=t) == []


# -- a target that did not take is sent once more (controller.py rule 11) ---------------------
@pytest.mark.parametrize("fault", ["lost", "garbled"])
def test_a_target_the_line_lost_is_sent_once_more_and_the_rotor_goes(rig: Rig, fault: str) -> None:
    """The frame lost, or garbled into one the box ignores (``AZ`` read as ``AJ``): no
    movement a reading shows, so the same bearing goes again, and the rotor turns to it with
    no error (before: a stall error 10 s later that blamed the brake)."""
    v = settled(ready(rig, start_az_deg=100, start_el_deg=10))
    t = v.now
    if fault == "lost":
        v.drop_writes(b"AZ200.0 EL10.0\n")
    else:
        v.garble_writes(b"AZ200.0 EL10.0\n", b"AJ200.0 EL10.0\n")
    v.target(200, 10)
    v.run_until(settled_at(200, 10), 60, "at 200")
    targets = [w for w in v.writes if w.t >= t and w.data == b"AZ200.0 EL10.0\n"]
    assert len(targets) == 2 and v.errors(since=t) == []
    settle = v.cfg.motion.settle_s
    assert settle < targets[1].t - targets[0].t < settle + 1.5


def test_a_rotor_jammed_from_the_start_is_still_a_stall_after_one_try_more(rig: Rig) -> None:
    v = settled(ready(rig, start_az_deg=100, start_el_deg=10))
    v.jam()
    t = v.now
    v.target(200, 10)
    v.run_until(lambda h: h.errors("stalled", since=t), 30, "the stall")
    took = v.now - t
    stall = v.cfg.motion.stall_timeout_s
    assert stall < took < stall + v.cfg.motion.settle_s + 1.5  # from the try that went
    assert v.sent(since=t).count(b"AZ200.0 EL10.0\n") == 2
    v.run_for(15)
    assert v.sent(since=t).count(b"AZ200.0 EL10.0\n") == 2 and len(v.errors(since=t)) == 1


def test_a_stop_before_the_try_more_ends_it(rig: Rig) -> None:
    v = settled(ready(rig, start_az_deg=100, start_el_deg=10))
    t = v.now
    v.drop_writes(b"AZ200.0 EL10.0\n")
    v.target(200, 10)
    v.run_for(0.5)
    v.stop()
    v.run_for(15)
    assert v.sent(since=t).count(b"AZ200.0 EL10.0\n") == 1
    assert v.truth().az_deg == 100 and v.errors(since=t) == []


# -- two real firmwares (easycomm.py rules 7 and 8; the emulator's rule 6) ---------------------
def el_of(model: str, el_deg: float) -> dict[str, float]:
    return {} if model.endswith("-az") else {"start_el_deg": el_deg}


@pytest.mark.parametrize("model", ["easycomm2", "easycomm3", "easycomm2-az", "easycomm3-az"])
def test_a_satnogs_controller_is_never_turned_by_a_poll(rig: Rig, model: str) -> None:
    """Its firmware reads a bare ``AZ`` as "turn to 0": an azimuth model that asked so turned
    the rotor from 200 to 0 at its first poll, unanswered, and called the controller silent."""
    v = ready(rig, model, firmware="satnogs", start_az_deg=200, **el_of(model, 20))
    v.run_for(30)
    assert v.frames("move") == [] and v.truth().az_deg == 200
    assert v.status.available and v.status.bearing_deg == 200 and v.errors() == []
    v.target(150, 30)
    v.run_until(lambda h: h.state is IDLE and h.truth().az_deg == 150, 60, "at 150")
    assert [f.data for f in v.frames("move")] == (
        [b"AZ150.0 EL30.0"] if model in ("easycomm2", "easycomm3") else [b"AZ150.0"]
    )


@pytest.mark.parametrize(
    ("model", "answer"),
    [
        ("easycomm2", b"+200.0 +20.0\n"),
        ("easycomm2-az", b"+200.0 ?\n"),
        ("easycomm3-separate", b"+20.0\n"),
    ],
)
def test_a_k3ng_controller_is_read_turned_and_stopped(rig: Rig, model: str, answer: bytes) -> None:
    """Its default build answers a bare ``AZ`` and ``EL`` with signed values alone: the bridge
    never came online with it."""
    v = ready(rig, model, firmware="k3ng", start_az_deg=200, **el_of(model, 20))
    assert answer in b"".join(data for _, data in v.received)
    assert v.status.available and v.status.bearing_deg == 200 and v.errors() == []
    if model != "easycomm2-az":
        assert v.status.elevation_deg == 20
    v.target(300, 40)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 220, 30, "turning")
    v.stop()
    v.run_until(lambda h: h.state is IDLE, 10, "stopped")
    assert not v.truth().is_moving and 220 < v.truth().az_deg < 235
    assert v.status.bearing_deg == pytest.approx(v.truth().az_deg, abs=0.051)
    assert v.errors() == []


@pytest.mark.parametrize("model", ["easycomm2", "easycomm2-az"])
def test_a_satnogs_answer_to_a_stop_is_no_junk_and_no_reading(rig: Rig, model: str) -> None:
    """Its firmware answers ``SA SE`` with the position (rule 9): it was told on R/error as
    bytes that are no reply at every stop."""
    v = ready(rig, model, firmware="satnogs", start_az_deg=200, **el_of(model, 20))
    for bearing in (300, 100):
        v.target(bearing) if model.endswith("-az") else v.target(bearing, 40)
        v.run_until(lambda h: h.state is MOVING and abs(h.truth().az_deg - 200) > 20, 30, "on")
        v.stop()
        v.run_until(lambda h: h.state is IDLE, 10, "stopped")
        v.run_for(5)
    assert b"SA SE\n" in v.sent() and v.errors() == []
    assert v.status.bearing_deg == pytest.approx(v.truth().az_deg, abs=0.051)


@pytest.mark.parametrize("firmware", ["generic", "k3ng", "satnogs"])
def test_a_double_stop_right_after_a_poll_loses_no_reading(rig: Rig, firmware: str) -> None:
    """Rule 9: a stop written while a poll's answer is on its way is answered after it. The
    poll's answer was taken for the stop's: on a controller that answers no stop the poll
    waited out its reply time, the codec took the controller for one that answers stops, the
    STOP's repeat ate the next poll's answer too, and with the rig's timings (the integration
    tests': a 1 s silence timeout) the rotator went offline, the next target refused. A
    SatNOGS answers both, the poll first: its answer to the stop is still no reading."""
    settings = {"idle_poll_interval_s": 0.3, "moving_poll_interval_s": 0.1, "settle_s": 0.6}
    v = rig(
        "easycomm2",
        settings={**settings, "stall_timeout_s": 2.5, "silence_timeout_s": 1.0},
        emulator={**FAST, "firmware": firmware, "start_az_deg": 10},
    )
    v.run_until_state(IDLE, 30)
    v.run_until(lambda h: h.writes[-1] == Sent(h.now, b"AZ EL\n"), 5, "a poll just written")
    t = v.now
    v.target(300, 0)  # (its answer still on the line)
    v.stop()
    v.run_for(0.05)
    v.stop()  # the main connection's copy of the lane's STOP (lastword.py rule 1)
    v.run_for(3)
    assert v.errors() == [] and all(s.available for s in v.published(since=t))
    assert v.state is IDLE and v.status.bearing_deg == pytest.approx(v.truth().az_deg, abs=0.051)


@pytest.mark.parametrize("model", ["easycomm3", "easycomm2-separate"])
def test_a_poll_answered_after_its_reply_time_around_a_stop_is_told_nowhere(
    rig: Rig, model: str
) -> None:
    """protocols/easycomm.py rule 10: a loaded host (a CI run at load 23) had the answer of the
    poll written with a STOP after its reply time; the next poll took it, and that poll's own
    answer, a line later, was told on R/error as bytes that are no reply. The rotor still
    stops where it was, every reading is the controller's, and the next target arrives."""
    settings = {"idle_poll_interval_s": 0.3, "moving_poll_interval_s": 0.1, "settle_s": 0.6}
    v = rig(
        model,
        settings={**settings, "stall_timeout_s": 2.5, "silence_timeout_s": 1.0},
        emulator={**FAST, "start_az_deg": 10},
    )
    v.run_until_state(IDLE, 30)
    v.target(300, 0)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 30, 30, "turning")
    poll = b"AZ\nEL\n" if model.endswith("-separate") else b"AZ EL\n"
    t = v.stopped_with_late_answers(poll, 0.6)  # past the reply time (0.4 s)
    truth = v.truth()
    assert not truth.is_moving and v.status.bearing_deg == pytest.approx(truth.az_deg, abs=0.051)
    v.target(90, 0)
    v.run_until(settled_at(90, 0), 60, "at 90")
    assert v.errors() == [] and all(s.available for s in v.published(since=t))
