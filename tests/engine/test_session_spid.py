"""A SPID Rot2Prog in virtual time: direct re-targeting and the controller's pulse grid.

The Rot2Prog takes a new set frame at any time and simply heads for it (no brake, no stop
needed), so the bridge sends a new target straight out (motion.plan_target, ``direct_retarget``).
Its positions live on a grid of 1/PH degree (PH pulses per degree, learned from its replies);
a set frame carries floor(PH * (360 + angle)), so a target snaps down to the grid
(protocols/spid.py rule 1) and the status shows the target the rotor will really get.
The line is 600 baud and half duplex: one poll exchange takes about 0.4 s.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from bridge.emulators.spid_models import K_SET, K_STATUS, K_STOP, Outcome
from tests.engine.test_session_rotorez import reconnected_mid_turn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING
STOP_FRAME = b"W" + bytes(10) + bytes([K_STOP]) + b" "


def ready(rig: Rig, ppd: int = 2) -> VirtualRotator:
    v = rig("rot2prog", emulator={"resolution_ppd": ppd})
    v.run_until_state(IDLE, 30)
    return v


def sets(v: VirtualRotator, since: float = float("-inf")) -> list[tuple[int, int]]:
    """The pulses of every set frame the controller took: (H, V)."""
    return [
        (int(f.data[1:5]), int(f.data[6:10]))
        for f in v.frames(Outcome.SET, since=since)
        if f.data[11] == K_SET
    ]


def settled_at(az: float, el: float) -> Callable[[VirtualRotator], bool]:
    def there(v: VirtualRotator) -> bool:
        truth = v.truth()
        return (
            v.state is IDLE
            and not truth.is_moving
            and truth.az_deg == pytest.approx(az)
            and truth.el_deg == pytest.approx(el)
        )

    return there


def assert_half_duplex(v: VirtualRotator) -> None:
    """Nothing was written while a reply was still owed (controller.py rule 3, link rule 3): at
    every write, all the replies owed by the frames before it had arrived whole."""
    reply_bytes = v.cfg.spec.reply_bytes
    owed = 0
    for w in v.writes:
        got = sum(len(data) for t, data in v.received if t <= w.t)
        assert got >= owed * reply_bytes, f"{w.data!r} written at {w.t:.3f} into a reply"
        owed += w.data[11] in (K_STATUS, K_STOP)


def test_a_new_target_while_turning_goes_straight_out_without_a_stop(rig: Rig) -> None:
    v = ready(rig)
    v.target(100, 30)
    v.run_for(20)
    assert v.truth().is_moving and v.state is MOVING
    t = v.now
    v.target(10, 5)
    v.run_until(lambda v: len(sets(v, t)) == 1, 2, "the new set frame")

    took = v.frames(since=t)[-1].time_s - t
    exchange_s = v.cfg.spec.exchange_time_s(v.cfg.baud)
    assert took <= exchange_s + 13 * 10 / v.cfg.baud + 0.01  # at most a reply in flight first
    assert v.truth().is_moving  # never stopped on the way
    assert {f.data[11] for f in v.frames(since=t)} <= {K_STATUS, K_SET}  # no stop frame
    v.run_until(settled_at(10, 5), 120, "at 10/5")

    assert not [f for f in v.frames() if f.data[11] == K_STOP]
    assert not [e for e in v.device.events if e.kind == "stopped"]
    assert sets(v) == [(2 * 460, 2 * 390), (2 * 370, 2 * 365)]
    assert_half_duplex(v)
    assert v.errors() == []


def test_targets_snap_down_to_the_pulse_grid_and_the_status_shows_where_it_goes(
    rig: Rig,
) -> None:
    v = ready(rig, ppd=4)
    t = v.now
    v.target(10.3, 5.6)  # 4 pulses a degree: 10.25 / 5.5
    v.run_for(2)
    assert sets(v, t) == [(1481, 1462)]
    assert (v.status.target_az_deg, v.status.target_el_deg) == (10.25, 5.5)

    v.target(10.45, 5.7)  # the same grid point: the rotor is already on its way there
    v.run_until(settled_at(10.25, 5.5), 60, "at 10.25/5.5")
    assert sets(v, t) == [(1481, 1462)]

    # the controller reports 10.25 as 10.2 (tenths, rounded down): within tolerance, arrived
    assert (v.status.bearing_deg, v.status.elevation_deg) == (10.2, 5.5)
    assert v.status.target_az_deg is None
    v.target(10.3, 5.6)  # already there, as far as the grid allows: nothing to send
    v.run_for(5)
    assert sets(v, t) == [(1481, 1462)] and v.errors() == []


def test_a_stream_of_targets_is_followed_without_flooding_the_line(rig: Rig) -> None:
    v = ready(rig)
    t = v.now
    for az in range(100, 200):  # 100 targets, 10 ms apart
        v.target(az, 10)
        v.run_for(0.01)
    v.run_until(settled_at(199, 10), 300, "at 199/10")

    assert 1 <= len(sets(v, t)) <= 3
    assert sets(v, t)[-1] == (2 * (360 + 199), 2 * 370)
    assert_half_duplex(v)


def test_turned_away_from_its_target_is_reported_and_stopped_once_at_rest(rig: Rig) -> None:
    """Motion rule 5 (cold review): a front-panel turn, or a controller driving the wrong way
    into its end stop, dropped the target with a log line only, and nothing was ever sent: no
    error on R/error, no stop for a motor still pushing against its stop."""
    v = ready(rig)
    v.target(100)
    v.run_until(lambda h: h.truth().is_moving and h.truth().az_deg > 20, 30, "turning")
    t = v.now
    v.manual_rotate(0.0)  # the panel sends it the other way
    v.run_until(lambda h: h.errors(since=t), 60, "reported")
    (report,) = v.errors(since=t)
    assert "turned away from its target" in report.message
    assert v.status.target_az_deg is None
    v.run_until(lambda h: not h.truth().is_moving, 120, "at rest")
    v.run_until(lambda h: h.frames(Outcome.STOP, since=t), 30, "a stop once at rest")
    assert len(v.frames(Outcome.STOP, since=t)) == 1
    assert not [f for f in v.frames(Outcome.SET, since=t)]  # it was never sent back


def test_a_move_by_hand_after_a_turned_away_rotor_was_stopped_is_left_alone(rig: Rig) -> None:
    """stops.py rule 4: the stop a turned-away rotor gets once at rest ends nothing a later
    move by hand could be taken for (an attack pass: recording it as a stop of a turn had the
    bridge stop the operator's next front-panel move as "still turning after a stop")."""
    v = ready(rig)
    v.target(100)
    v.run_until(lambda h: h.truth().is_moving and h.truth().az_deg > 20, 30, "turning")
    t = v.now
    v.manual_rotate(0.0)
    v.run_until(lambda h: h.frames(Outcome.STOP, since=t), 120, "a stop once at rest")
    v.run_for(20)
    t = v.now
    v.manual_rotate(200.0)  # the operator turns it by hand again
    v.run_until(lambda h: h.state is MOVING, 10, "seen turning")
    v.run_until(lambda h: not h.truth().is_moving, 300, "at rest")
    assert v.frames(Outcome.STOP, since=t) == [] and v.errors(since=t) == []
    assert round(v.truth().az_deg) == 200


def test_a_turned_away_rotors_stop_the_port_failed_right_after_is_owed(rig: Rig) -> None:
    """stops.py rules 3 and 4: the stop a turned-away rotor gets once at rest, lost as the
    port failed, is the first frame the reopened port gets."""
    v = ready(rig)
    v.target(100)
    v.run_until(lambda h: h.truth().is_moving and h.truth().az_deg > 20, 30, "turning")
    v.drop_writes(STOP_FRAME)
    v.manual_rotate(0.0)
    v.run_until(lambda h: h.errors("stalled"), 60, "reported")
    v.run_until(lambda h: any(w.lost for w in h.writes), 120, "its stop, lost once at rest")
    v.link_down()
    v.run_for(0.5)
    t = v.now
    v.link_up()
    v.run_for(0.5)
    assert v.sent(since=t)[:1] == [STOP_FRAME]
    assert Outcome.STOP in [f.outcome for f in v.frames(since=t)]


def test_a_stall_stop_before_a_new_target_is_not_owed_when_the_port_fails_twice(
    rig: Rig,
) -> None:
    """stops.py rule 3: a target written after a stall's stop leaves no stop owed, also when
    the port fails, comes back and fails again within the second (an attack pass: the second
    failure owed the stall's stop, and it stopped the new move a degree into it)."""
    v = ready(rig)
    v.target(100)
    v.run_until(lambda h: h.truth().is_moving and h.truth().az_deg > 20, 30, "turning")
    v.jam()
    v.run_until(lambda h: h.errors("stalled"), 60, "the stall")
    t = v.now
    v.unjam()
    v.run_for(0.1)
    v.target(200)
    v.run_until(lambda h: h.frames(Outcome.SET, since=t), 5, "the new target at the box")
    v.link_down()
    v.run_for(0.05)
    v.link_up()
    v.run_for(0.05)
    v.link_down()
    v.run_for(0.5)
    t = v.now
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 400, "at rest")
    assert v.frames(Outcome.STOP, since=t) == [] and round(v.truth().az_deg) == 200


def _states(v: VirtualRotator) -> list[MotionState]:
    """The published states in order, each change once."""
    out: list[MotionState] = []
    for _t, status in v.statuses:
        if not out or status.state is not out[-1]:
            out.append(status.state)
    return out


@pytest.mark.parametrize("model", ["md01", "rot2prog"])
def test_a_controller_without_a_brake_is_never_shown_braking(rig: Rig, model: str) -> None:
    """An idle MD-01 at start goes offline -> idle, and a move ends idle again: it has no brake
    (motion rule 4), so ``braking`` would be untrue."""
    v = rig(model, emulator={"start_az_deg": 100})
    v.run_for(10)
    assert _states(v) == [MotionState.OFFLINE, IDLE]
    v.target(150)
    v.run_until(lambda h: h.state is IDLE and h.truth().az_deg > 140, 60, "arrived")
    v.run_for(5)
    assert _states(v) == [MotionState.OFFLINE, IDLE, MOVING, IDLE]


def flip_ph_once(v: VirtualRotator) -> list[bool]:
    """The next reply's PH byte, 2, turned into 10 on the line (one bit); the list returned
    holds True once it was (the controller sends byte by byte)."""
    at, done = [-1], []

    def flip(data: bytes, now: float) -> bytes:
        out = bytearray()
        for b in data:
            if not done and at[0] < 0 and b == 0x57:
                at[0] = 0
            elif not done and 0 <= at[0] < 12:
                at[0] += 1
                if at[0] == 5 and b == 2:
                    b = 10
                    done.append(True)
            out.append(b)
        return bytes(out)

    v.to_host = flip
    return done


def test_a_resolution_byte_flipped_on_the_line_never_sends_the_rotor_to_its_end_stop(
    rig: Rig,
) -> None:
    """protocols/spid.py rule 5: one reply's PH, 2 flipped to 10; the next target (20/5) went
    out as 3800/3650 pulses, and the rotor ran to azimuth 540 and elevation 210."""
    v = ready(rig)
    v.run_for(3)
    flipped = flip_ph_once(v)
    v.run_until(lambda h: flipped, 10, "a reply's PH flipped")
    v.run_for(0.05)
    v.to_host = None
    t = v.now
    v.target(20, 5)
    v.run_until(lambda h: h.state is IDLE and sets(h, since=t), 60, "there")
    assert sets(v, since=t) == [(760, 730)]
    assert (v.truth().az_deg, v.truth().el_deg) == (20.0, 5.0)


def test_the_first_reply_of_a_connection_with_a_flipped_resolution_counts_no_target(
    rig: Rig,
) -> None:
    """protocols/spid.py rule 5 at connect: the first reply's PH flipped 2 to 10 set the
    resolution on one word; a target right after went out as 3800 pulses (azimuth 540). A
    connection's first resolution waits for a second reading that says it too."""
    v = rig("rot2prog", emulator={"resolution_ppd": 2})
    flipped = flip_ph_once(v)  # (the first reply's)
    v.run_until(lambda h: h.status.available, 30, "online")
    v.to_host = None
    t = v.now
    v.target(20, 5)
    v.run_until(lambda h: h.state is IDLE and sets(h, since=t), 60, "there")
    assert flipped
    assert sets(v, since=t) == [(760, 730)]
    assert (v.truth().az_deg, v.truth().el_deg) == (20.0, 5.0)


def test_a_glitched_frame_before_the_real_reply_is_no_reading(rig: Rig) -> None:
    """link.py rule 9, the same shape as the Rotor-EZ's: a well-formed frame saying 359 deg
    just before the real reply of one status exchange. Neither is taken: no 359 published, no
    move in rotor health, the controller asked again."""
    v = ready(rig)
    v.run_for(10)
    bearing, health = v.status.bearing_deg, v.status.health
    assert health is not None and bearing is not None and abs(bearing - 359.0) > 1
    glitch_frame = bytes([0x57, 7, 1, 9, 0, 2, 3, 6, 0, 0, 2, 0x20])  # az 359.0, el 0.0
    glitched: list[float] = []

    def glitch(data: bytes, now: float) -> bytes:
        if glitched or data[:1] != b"\x57":
            return data
        glitched.append(now)
        return glitch_frame + data

    v.to_host = glitch
    t = v.now
    v.run_for(30)
    assert glitched
    assert {s.bearing_deg for s in v.published(since=t)} <= {bearing}
    assert v.status.health is not None and v.status.health.moves == health.moves
    assert v.state is IDLE and v.status.bearing_deg == bearing


@pytest.mark.parametrize("model", ["rot2prog", "rot1prog", "md01"])
def test_a_stop_in_the_quiet_time_after_a_reply_goes_out_at_once(rig: Rig, model: str) -> None:
    """link.py rule 9 and rule 3: a reading is held for a few byte times of quiet after its
    reply (50 ms at the Rot2Prog's 600 baud), but a reply that came whole is no reply owed. A
    STOP pressed in that time is on the wire the same instant, the rotor stops, and the line
    stays half duplex (the stop's reply is its own, not a second reply of the poll)."""
    v = rig(model, emulator={"start_az_deg": 100})
    v.run_until_state(IDLE, 30)
    v.target(150)
    v.run_until(lambda h: h.state is MOVING and h.truth().is_moving, 30, "moving")
    reply_bytes = v.cfg.spec.reply_bytes

    def whole_reply_in(h: VirtualRotator) -> bool:
        last = h.writes[-1]
        got = sum(len(data) for t, data in h.received if t > last.t)
        return last.data[11] == K_STATUS and got >= reply_bytes

    v.run_until(whole_reply_in, 10, "a poll's whole reply")
    t = v.now
    v.stop()
    stop = bytes([0x57, *bytes(10), 0x0F, 0x20])
    assert [(w.t, w.data) for w in v.writes if w.t >= t] == [(t, stop)]  # at once
    v.run_until(lambda h: h.state is IDLE and not h.truth().is_moving, 30, "stopped")
    assert v.truth().az_deg < 149 and v.sent(since=t).count(stop) == 1  # it took: no second
    assert_half_duplex(v)


@pytest.mark.parametrize("model", ["rot2prog", "rot1prog"])
@pytest.mark.parametrize("lost, seen_turning", [(1, True), (2, False)])
def test_a_stop_lost_after_a_reconnect_mid_turn_is_sent_again(
    rig: Rig, model: str, lost: int, seen_turning: bool
) -> None:
    """controller.py rule 3: the turn seen by an idle poll (Rot2Prog every 9.3 s), and a stop
    written, are followed at the moving rate. The next reading stayed on the idle grid: the
    rotor was taken for stopped for want of readings within its settle time, and a STOP the
    line lost (pressed once the turn was shown, or right after the first reading and lost
    twice) was never sent again (an attack pass: it ran on to 170, R/state flipping moving and
    idle)."""
    v = reconnected_mid_turn(rig, model)
    if seen_turning:
        v.run_until_state(MOVING, 40)
    stop = v.cfg.spec.codec_factory().encode_stop()
    v.drop_writes(stop, lost)
    t = v.now
    v.stop()
    v.run_for(60)
    assert not v.truth().is_moving and v.truth().az_deg < 100
    assert v.sent(since=t).count(stop) >= lost + 1


def test_an_azimuth_or_an_elevation_alone_keeps_the_other_axis_on_its_step(rig: Rig) -> None:
    """At 4 pulses a degree the box reads 44.25 as 44.2, and 44.2 asked for is 44.0 (rule 1's
    floor): an axis sent alone asks for the other's own step, as the box read it, so the other
    axis does not creep down a step at every such target."""
    v = rig(
        "rot2prog", emulator={"resolution_ppd": 4, "start_az_deg": 120.75, "start_el_deg": 44.25}
    )
    v.run_until_state(IDLE, 30)
    t = v.now
    v.target(130)
    v.run_until(settled_at(130, 44.25), 60, "at 130, the elevation where it was")
    v.target(None, 40.75)
    v.run_until(settled_at(130, 40.75), 60, "at 40.75 of elevation, the azimuth where it was")
    assert sets(v, t) == [(4 * 490, 4 * 404 + 1), (4 * 490, 4 * 400 + 3)]


@pytest.mark.parametrize("model", ["rot2prog", "rot1prog", "md01"])
def test_a_rotor_coasting_after_a_stop_is_shown_at_rest_where_it_came_to_rest(
    rig: Rig, model: str, caplog: pytest.LogCaptureFixture
) -> None:
    """emulators/spid.py rule 11 (spid.txt: the stop's answer "often off by a degree or two"):
    the rotor runs on 2 degrees over a second after an operator's STOP. The readings show it
    turning after the stop, but with its motor off (motion.py ``coast_end``): one stop frame,
    no warning in the log (there was one, and a second stop, after every stop), no error on
    R/error, ``moving`` then ``idle`` once, no target, the bearing where it came to rest."""
    caplog.set_level(logging.WARNING, logger="bridge")
    v = rig(model, emulator={"coast_deg": 2.0, "coast_s": 1.0})
    v.run_until_state(IDLE, 30)
    v.target(100)
    v.run_until(lambda h: h.truth().is_moving and h.truth().az_deg > 20, 60, "turning")
    t = v.now
    v.stop()
    v.run_until(lambda h: h.frames(Outcome.STOP, since=t), 5, "the stop at the box")
    stopped_at = v.frames(Outcome.STOP, since=t)[0].time_s
    v.run_for(30)

    coasted = [e for e in v.device.events if e.kind == "coasted" and e.time_s >= stopped_at]
    assert coasted and coasted[0].time_s == pytest.approx(stopped_at + 1.0)
    rest = v.truth().az_deg
    assert not v.truth().is_moving and rest > 20
    assert v.errors(since=t) == []
    assert _states_since(v, t) == [MOVING, IDLE]
    assert v.status.target_az_deg is None and v.status.bearing_deg == pytest.approx(rest, abs=1)
    assert len(v.frames(Outcome.STOP, since=t)) == 1 and not v.frames(Outcome.SET, since=t)
    assert not [r for r in caplog.records if "still turning" in r.getMessage()]

    t = v.now  # a target right after a stop goes out at once, coast or not
    v.target(50)
    v.run_for(0.2)
    v.stop()
    v.run_for(0.5)
    v.target(10)
    v.run_until(lambda h: h.state is IDLE and not h.truth().is_moving, 120, "at 10")
    assert round(v.truth().az_deg) == 10 and v.errors(since=t) == []
    assert v.status.target_az_deg is None


def _states_since(v: VirtualRotator, since: float) -> list[MotionState]:
    out: list[MotionState] = []
    for t, status in v.statuses:
        if t >= since and (not out or status.state is not out[-1]):
            out.append(status.state)
    return out
