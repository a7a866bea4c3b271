"""The last word in the session (session rules 11-13, mailbox rules 6-7), in virtual time with
the Rotor-EZ emulator: what the controller understood and where the rotor ends.

The two MQTT connections are stood in for by what they put in the mailbox: the stop lane's
stop with its hold, the main connection's copies in order, and the release its marker brings
(interfaces/mqtt/lastword.py; the real-broker orderings are in tests/integration/test_last_word.py).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

import bridge.feature
from bridge.core.model import FeatureCommand, MotionState, Source, Stop, Target, TargetInfo
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.features import FEATURES
from bridge.session.follow import Follow, Heard
from bridge.session.stops import EXPRESS_LOST
from bridge.session.tracking import Track
from bridge.sky import Body, Sky
from tests.engine.test_feature_commands import TOY
from tests.engine.test_follow import STATION as FOLLOWING
from tests.engine.test_session_tracking import SUN_EPOCH, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.support.sky import synthetic_tle

Rig = Callable[..., VirtualRotator]
IDLE = MotionState.IDLE


def ready(rig: Rig, **kw: object) -> VirtualRotator:
    v = rig("rotorez", **kw)
    v.run_until_state(IDLE, 30)
    return v


def bearings(v: VirtualRotator, since: float = float("-inf")) -> list[bytes]:
    return [f.data for f in v.frames(*BEARING_OUTCOMES, since=since)]


def test_a_target_read_after_a_lane_stop_waits_and_the_main_copy_of_the_stop_drops_it(
    rig: Rig,
) -> None:
    v = ready(rig)
    v.target(200)
    v.run_until(lambda h: h.truth().is_moving, 10, "turning")
    t = v.now
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # the lane's stop
    v.mailbox.put(Target(300.0))  # the main connection: published before the stop
    v._take()
    v.run_for(8)  # the rotor stopped and braked; the held target did not go out
    assert bearings(v) == [b"AP1200\r"] and not v.truth().is_moving
    stopped_at = v.truth().az_deg
    v.stop()  # the main connection's copy of the stop: drops the target before it
    v.target(250)  # published after the stop
    v.run_for(8)
    assert bearings(v) == [b"AP1200\r"]  # still held: the marker is not back
    assert v.truth().az_deg == stopped_at
    v.mailbox.put_release(1)
    v._take()
    v.run_until(lambda h: h.state is IDLE and abs(h.truth().az_deg - 250) < 4, 120, "at 250")
    assert bearings(v) == [b"AP1200\r", b"AP1250\r"]
    assert t < v.now


def held_behind_a_stop(v: VirtualRotator) -> None:
    """A stop with the stop express's hold 1 (express.py rule 8), and a target to 120
    published just after it, taken together."""
    v.mailbox.put_express_hold(1)
    v.mailbox.put(Stop(Source.MQTT))
    v.mailbox.put(Target(120.0))
    v._take()


def test_a_target_after_a_stop_waits_for_the_stop_expresss_answer(rig: Rig) -> None:
    """interfaces/mqtt/express.py rule 8: the express may still write its frame for the stop; the
    move read after the stop goes out only when the express answered for it."""
    v = ready(rig)
    t = v.now
    held_behind_a_stop(v)
    v.run_for(8)
    assert bearings(v, since=t) == [] and not v.truth().is_moving
    v.mailbox.put_express_release(1)
    v._take()
    v.run_until(lambda h: h.state is IDLE and abs(h.truth().az_deg - 120) < 4, 120, "at 120")
    assert bearings(v, since=t) == [b"AP1120\r"]


def test_a_target_waiting_for_an_express_that_lost_its_connection_is_dropped(rig: Rig) -> None:
    """stops.py rule 5, an attack pass: a firewall dropped the express's flow alone; its hold
    ended only when its keepalive noticed, and the target sent after the STOP then went out
    45 s late, unasked. Ended by the express's loss, what waited is dropped and said."""
    v = ready(rig)
    t = v.now
    held_behind_a_stop(v)
    v.run_for(45)
    v.mailbox.put_express_release(1, lost=True)
    v._take()
    v.run_for(20)
    assert bearings(v, since=t) == [] and not v.truth().is_moving
    assert v.status.last_error == f"target dropped: {EXPRESS_LOST}"
    v.target(150)  # sent again: it goes
    v.run_until(lambda h: h.state is IDLE and abs(h.truth().az_deg - 150) < 4, 120, "at 150")


def test_a_target_taken_with_the_express_losing_its_connection_is_dropped_too(rig: Rig) -> None:
    """A review: a target that waited in the mailbox's batch (taken with the lost release,
    not before it) went out; the one the session held was dropped."""
    v = ready(rig)
    t = v.now
    v.mailbox.put_express_hold(1)
    v.mailbox.put(Stop(Source.MQTT))
    v._take()
    v.run_for(45)
    v.mailbox.put(Target(120.0))  # published while the hold waits
    v.mailbox.put_express_release(1, lost=True)  # (taken in one batch)
    v._take()
    v.run_for(20)
    assert bearings(v, since=t) == [] and not v.truth().is_moving
    assert v.status.last_error == f"target dropped: {EXPRESS_LOST}"


def test_a_hold_ended_by_a_lost_connection_drops_what_waited(rig: Rig) -> None:
    """Rule 13: the target's place in line is lost; it is reported, never carried out."""
    v = ready(rig)
    t = v.now
    v.mailbox.put(Stop(Source.MQTT), hold=3)
    v.mailbox.put(Target(300.0))  # its copy of the stop never came: the connection dropped
    v._take()
    v.mailbox.put_release(0, clear=True)
    v.mailbox.put(Target(120.0))  # the new connection's: newer, stays
    v._take()
    v.run_until(lambda h: h.state is IDLE and abs(h.truth().az_deg - 120) < 4, 120, "at 120")
    assert bearings(v, since=t) == [b"AP1120\r"]
    assert any("connection that would have told" in e.message for e in v.errors())


def test_a_lock_on_then_off_in_one_batch_still_stops_the_rotor(rig: Rig) -> None:
    """Mailbox rule 7: the ON's stop is not lost to the OFF that followed it."""
    v = ready(rig)
    v.target(200)
    v.run_until(lambda h: h.truth().is_moving, 10, "turning")
    stops = len(v.frames("stop"))
    v.mailbox.put_lock(True)
    v.mailbox.put_lock(False)
    v._take()
    v.run_for(1)
    assert len(v.frames("stop")) > stops
    assert not v.truth().is_moving
    assert v.status.locked is False


def test_a_stop_while_the_port_is_closed_is_the_first_frame_once_it_is_open(rig: Rig) -> None:
    """Rule 11: the rotor turning when the adapter dropped out is stopped when it is back."""
    v = ready(rig)
    v.target(200)
    v.run_until(lambda h: h.truth().is_moving, 10, "turning")
    v.link_down("unexpected error")
    v.stop()
    v.run_for(2)
    t = v.now
    v.link_up()
    v.run_for(0.5)
    assert v.sent(since=t)[0] == b";;"  # (a connection's first stop: rotorez.py rule 8)
    assert v.frames(since=t)[0].outcome == "stop"
    v.run_for(2)
    assert not v.truth().is_moving


def test_a_waiting_locator_target_is_the_current_one_and_a_success_clears_the_last_error(
    rig: Rig,
) -> None:
    """Tried as a new user: a locator target that waits out the brake shows its place (the
    console and ``long`` need it), and the last error goes once a command is carried out."""
    v = ready(rig)
    v.target(200)
    v.run_until(lambda h: h.truth().is_moving, 10, "turning")
    v.stop()  # the rotor brakes for 5 s: a target now waits
    v.mailbox.put_note("azimuth 999 out of range")  # a refusal the judge made
    v._take()
    assert v.status.last_error == "azimuth 999 out of range"
    info = TargetInfo(-35.3, 149.1, 16000.0, 120.0, 300.0, locator="QF44")
    v.command(Target(120.0, None, Source.MQTT, info=info))
    assert v.status.target_info == info  # waiting out the brake, already the current one
    assert v.status.last_error is None


@pytest.mark.parametrize("halt", ["stop", "lock"])
def test_a_halt_ends_the_place_of_the_target_it_dropped(rig: Rig, halt: str) -> None:
    """An attack pass: after a lock ON the status still showed the locator target it had
    stopped (Home Assistant's distance to it), and a "long path" button press then turned the
    rotor to that cancelled target's long path; after a STOP it did not."""
    v = ready(rig)
    info = TargetInfo(-35.3, 149.1, 16000.0, 120.0, 300.0, locator="QF44")
    v.command(Target(120.0, None, Source.MQTT, info=info))
    v.run_until(lambda h: h.truth().is_moving, 10, "turning")
    assert v.status.target_info == info
    v.stop() if halt == "stop" else v.lock(True)
    assert v.status.target_info is None
    if halt == "lock":
        v.lock(False)
        assert v.status.target_info is None


def test_a_stop_lost_on_the_line_is_sent_again_while_a_held_target_waits(rig: Rig) -> None:
    """Rule 5's check of a stop goes on while a target is held (it is not going out)."""
    v = rig("rotorez", emulator={"start_az_deg": 10, "speed_deg_s": 5.0})
    v.run_until_state(IDLE, 30)
    v.target(300)
    v.run_until(lambda h: h.truth().is_moving, 10, "turning")
    v.drop_writes(b";")  # the lane's stop is lost on the line (RF)
    v.mailbox.put(Stop(Source.MQTT), hold=1)
    v.mailbox.put(Target(250.0))  # the main connection's, published after it: held
    v._take()
    v.run_for(10)
    assert not v.truth().is_moving
    assert len(v.frames("stop")) >= 1


def test_a_stop_waiting_for_a_half_duplex_line_is_sent_first_when_the_port_is_back(
    rig: Rig,
) -> None:
    """Rule 11: the port failed while a poll's reply was owed and the stop waited for it."""
    v = rig("rot2prog")
    v.run_until_state(IDLE, 30)
    v.target(200, 10)
    v.run_until(lambda h: h.truth().is_moving, 20, "turning")
    v.run_until(
        lambda h: h.session.controller.link is not None and h.session.controller.link.reply_owed,
        5,
        "a reply owed",
    )
    v.stop()
    assert (
        v.session.controller.link is not None and v.session.controller.link.stop_due
    )  # not written yet
    v.link_down("USB adapter reset")
    v.run_for(1)
    t = v.now
    v.link_up()
    v.run_for(3)
    assert v.frames(since=t)[0].outcome == "stop"
    assert not v.truth().is_moving


@pytest.mark.parametrize("halt", ["lock", "stop"])
@pytest.mark.parametrize("model", ["rotorez", "gs232b", "easycomm2", "rot2prog", "md01"])
def test_a_halt_kept_across_a_restart_stops_the_rotor_on_the_first_connect(
    model: str, halt: str
) -> None:
    """Session rule 11, two attack passes: a lock ON, or a STOP, while the adapter was out
    (its stop owed), then the bridge restarted before the adapter came back: the state file
    gave the lock back but not the stop owed (and kept nothing of a STOP), and the rotor
    turned on to its target. The status says the stop is owed (the state file keeps it:
    runtime/kept.py rule 8), the next start owes it, and says so no more once it is written."""
    with VirtualRotator(model) as v:
        v.run_until_state(MotionState.IDLE, 90)
        v.target(170)
        v.run_for(5)
        v.link_down()
        v.run_for(0.3)
        if halt == "lock":
            v.lock(True)  # tower work; the port is out: its stop is owed, in this process
        else:
            v.stop()
        v.run_for(1)
        assert v.status.stop_owed
        device, now = v.device, v.now
    kept = {"locked": True} if halt == "lock" else {"stop_owed": True}
    with VirtualRotator(model, **kept, connect=False, start_s=now) as again:  # type: ignore[arg-type]
        again.device = device  # the same controller, still turning
        assert again.status.stop_owed  # (the first status says so: nothing saves it away)
        t = again.now
        again.link_up()
        again.run_for(30)
        stop = again.cfg.spec.codec_factory().encode_stop()
        # (the stop's own bytes first: a connection's first stop may carry a second copy,
        # protocols/base.py rule 9)
        assert again.sent(since=t)[0].startswith(stop[0] if isinstance(stop, list) else stop)
        assert not again.truth().is_moving and again.truth().az_deg < 150
        assert again.status.locked is (halt == "lock") and not again.status.stop_owed


@pytest.mark.parametrize("again", ["lock", "stop"])
def test_a_stop_owed_after_the_lock_was_released_is_checked_as_any(again: str) -> None:
    """stops.py rule 2: a locked start with the adapter out, the lock released, then (the
    adapter still out) the lock ON again or an operator's STOP: the stop owed is that one's,
    checked while the lock holds or until the next target, not let go as the released lock's
    (a review: a turn at the panel during the tower work went on to 300, no stop written)."""
    with VirtualRotator("gs232b", locked=True, connect=False) as v:
        v.run_for(5.0)
        v.lock(False)
        v.run_for(5.0)
        if again == "lock":
            v.lock(True)
        else:
            v.stop()
        v.run_for(5.0)
        v.link_up()
        v.run_until(lambda h: h.status.available and h.state is IDLE, 60, "online")
        v.run_for(600.0)
        t = v.now
        v.manual_rotate(300.0)
        v.run_for(60.0)
        assert b"S\r" in v.sent(since=t) and abs(v.truth().az_deg - 300.0) > 5


def turning_to_300(rig: Rig) -> VirtualRotator:
    """A GS-232B online, turning to 300 for 2 s."""
    v = rig("gs232b")
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.target(300.0)
    v.run_until(lambda h: h.truth().is_moving, 5, "moving")
    v.run_for(2)
    return v


def stopped_short_of_300(v: VirtualRotator) -> None:
    """Back online, the rotor stops: it is not let run on to the target the operator stopped."""
    v.run_until(lambda h: h.status.available, 10, "online again")
    v.run_for(5)
    assert not v.truth().is_moving and abs(v.truth().az_deg - 300.0) > 10, v.truth()


def locked_and_released_unheard(v: VirtualRotator) -> None:
    """Lock ON, and OFF half a second later, while the controller's replies are lost (it hears:
    the lock's stop takes, and no reading shows it)."""
    v.set_silent(True)
    v.lock(True)
    v.run_for(0.5)
    v.lock(False)


def not_stopped_by_hand_later(v: VirtualRotator) -> None:
    """Ten minutes on, the rotor turned by hand at its panel is not stopped (stops.py rule 2:
    the lock's release says the tower work is over)."""
    v.run_for(600.0)
    t = v.now
    v.manual_rotate(300.0)
    v.run_for(60.0)
    assert b"S\r" not in v.sent(since=t), v.sent(since=t)


def adapter_reset(v: VirtualRotator) -> None:
    """The USB adapter resets: the port fails, and opens again a second later."""
    v.link_down("USB adapter reset")
    v.run_for(1)
    v.link_up()


def test_a_stop_lost_just_before_the_controller_went_silent_goes_again_when_it_answers(
    rig: Rig,
) -> None:
    """stops.py rule 3: a noise burst eats a GS-232B's STOP and the polls around it (it hears
    no whole command and answers nothing: offline after 3 s). Back online, its readings show
    the rotor still turning to the target the operator stopped: the stop goes again, the first
    frame after the first reading (an attack pass: the rotor ran 26 s on to the cancelled
    target)."""
    v = turning_to_300(rig)
    v.set_deaf(True)  # the burst: nothing the host writes arrives whole
    v.run_for(0.5)
    v.stop()
    v.run_for(4)
    assert not v.status.available
    v.set_deaf(False)  # healed
    stopped_short_of_300(v)


def stop_and_target_lost(v: VirtualRotator, deaf_for_s: float) -> None:
    """A deaf burst eats the operator's STOP and the target to 100 sent after it; it goes on
    ``deaf_for_s`` after the target (the line still deaf at the end)."""
    v.set_deaf(True)
    v.run_for(0.3)
    v.stop()  # lost
    v.run_for(0.3)
    v.target(100.0)  # lost too
    v.run_for(deaf_for_s)


def test_a_stop_and_the_target_after_it_both_lost_before_a_silence_still_stop_the_rotor(
    rig: Rig,
) -> None:
    """stops.py rule 3 (a review's case, the last note's): a deaf burst eats the operator's STOP
    and the target sent after it. The target went out, so no stop was owed; the bridge drops
    the target at the silence, and back online the rotor ran on to the bearing before both.
    A target no reading came after leaves the stop before it owed."""
    v = turning_to_300(rig)
    stop_and_target_lost(v, 4)
    assert not v.status.available
    v.set_deaf(False)
    stopped_short_of_300(v)


def test_a_stop_and_the_target_after_it_lost_in_a_short_burst_do_not_leave_the_old_move(
    rig: Rig,
) -> None:
    """motion.py rule 5: the same two frames lost in a burst too short to be found silent. The
    rotor, still on its way to 300, passes the new bearing and turns on: it is stopped there,
    not let run 180 degrees on to the bearing the operator stopped, and the error says so."""
    v = turning_to_300(rig)
    stop_and_target_lost(v, 1.0)
    v.set_deaf(False)
    v.run_until(lambda h: h.truth().az_deg > 100.0, 60, "past 100")
    v.run_for(10)
    assert not v.truth().is_moving and v.truth().az_deg < 130.0, v.truth()
    assert any("past its target" in e.message for e in v.errors()), v.errors()


def stopped_then_turning_to_100(rig: Rig) -> VirtualRotator:
    """Turning to 300, stopped, then sent 100: a second into that turn."""
    v = turning_to_300(rig)
    v.stop()
    v.run_for(0.3)
    v.target(100.0)
    v.run_until(lambda h: h.truth().is_moving, 10, "turning to 100")
    v.run_for(1)
    return v


def test_a_target_heard_after_a_stop_clears_the_stop_owed(rig: Rig) -> None:
    """stops.py rule 3: a reading after the target shows the controller hearing again; the
    stop before that target is owed no more, and a port that fails later does not stop the
    new move. (A silence mid-turn stops it whatever came before: controller.py rule 2.)"""
    v = stopped_then_turning_to_100(rig)
    t = v.now
    v.link_down()
    v.run_for(1)
    v.link_up()
    v.run_until(lambda h: h.status.available, 10, "online again")
    v.run_until(lambda h: not h.truth().is_moving, 120, "at rest")
    assert abs(v.truth().az_deg - 100.0) < 4, v.truth()
    assert b"S\r" not in v.sent(since=t)


def test_a_silence_mid_turn_after_a_stop_and_a_target_heard_stops_the_new_move(
    rig: Rig,
) -> None:
    """controller.py rule 2: the same turn, its replies lost instead: offline with a stop sent
    (it hears: the rotor stops short of 100), and again when it answers (stops.py rule 3)."""
    v = stopped_then_turning_to_100(rig)
    t = v.now
    v.set_silent(True)  # it hears, its replies are lost: found silent
    v.run_until(lambda h: not h.status.available, 10, "offline")
    assert b"S\r" in v.sent(since=t)
    v.run_for(2)
    assert not v.truth().is_moving and abs(v.truth().az_deg - 100.0) > 10, v.truth()
    back = v.now
    v.set_silent(False)
    v.run_until(lambda h: h.status.available, 10, "online again")
    v.run_for(1)
    assert b"S\r" in v.sent(since=back)  # (owed: the first frame after its first reading)


def test_a_dcu1s_lock_on_whose_stop_frame_the_line_garbles_still_stops_the_rotor(
    rig: Rig,
) -> None:
    """stops.py rule 6: a DCU-1 reports nothing, so nothing can show a stop lost; its lock ON's
    one stop frame arrived with a bit flipped (``@S1;``) and the rotor turned on 27 s to its
    target while the operator climbed the tower (an attack pass). Every stop goes twice."""
    v = rig("dcu1")
    v.run_until(lambda h: h.status.available, 30, "online")
    v.target(300.0)
    v.run_until(lambda h: h.truth().is_moving, 30, "moving")
    v.run_for(3)
    t = v.now
    v.garble_writes(b"AS1;", b"@S1;")  # the lock's stop, one bit flipped on the line
    v.lock(True)
    v.run_for(10)
    assert not v.truth().is_moving, v.truth()
    assert v.sent(since=t).count(b"AS1;") == 2  # (the garbled one, and the second)


def test_a_stop_written_while_the_controller_is_offline_is_owed_when_it_answers(rig: Rig) -> None:
    """stops.py rule 3: the controller found silent mid-turn, no stop out; the operator, seeing
    it offline, sends STOP, written on the open port and lost. Back online, the rotor is
    stopped, not let run on to its target (a connection's first reading is a guess)."""
    v = turning_to_300(rig)
    v.set_deaf(True)
    v.run_for(4)
    assert not v.status.available
    v.stop()  # written, lost
    v.run_for(0.5)
    v.set_deaf(False)
    stopped_short_of_300(v)


def test_a_stop_unseen_when_the_port_fails_before_silence_is_found_is_owed(rig: Rig) -> None:
    """stops.py rule 3 (a review): a STOP lost on the line, then the USB adapter resets 1.5 s
    later (past STOP_UNSURE_S, before the silence timeout). The stop no reading showed taking
    is owed to the new connection: the rotor is stopped, not let run on to the target."""
    v = turning_to_300(rig)
    v.set_deaf(True)
    v.run_for(0.2)
    v.stop()  # lost
    v.run_for(1.5)
    v.link_down("USB adapter reset")
    v.set_deaf(False)
    v.run_for(0.5)
    v.link_up()
    stopped_short_of_300(v)


def test_the_locks_stop_resent_after_silence_is_let_go_as_released(rig: Rig) -> None:
    """stops.py rules 2 and 3 (a review): lock ON, lock OFF, and the controller's replies lost
    long enough for it to be found silent: its lock's stop goes again when it answers, but as
    the released lock's, so a turn by hand long after the tower work is not stopped."""
    v = rig("gs232b")
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    locked_and_released_unheard(v)
    v.run_for(4)
    assert not v.status.available
    v.set_silent(False)
    v.run_until(lambda h: h.status.available and h.state is IDLE, 60, "online")
    not_stopped_by_hand_later(v)


def test_a_dcu1s_owed_stop_on_reconnect_goes_twice(rig: Rig) -> None:
    """stops.py rule 6 (a review): the stop a DCU-1 is owed while its port is out (a lock ON
    then) goes twice too when the port opens: one flipped bit and the rotor turned on."""
    v = rig("dcu1")
    v.run_until(lambda h: h.status.available, 30, "online")
    v.target(300.0)
    v.run_until(lambda h: h.truth().is_moving, 30, "moving")
    v.run_for(3)
    v.link_down()
    v.run_for(0.3)
    v.lock(True)  # tower work; the port is out: its stop is owed
    v.run_for(1)
    t = v.now
    v.garble_writes(b"AS1;", b"@S1;")
    v.link_up()
    v.run_for(10)
    assert not v.truth().is_moving, (v.truth(), v.sent(since=t))


def test_an_owed_stop_written_at_re_answer_is_checked_at_the_moving_rate(rig: Rig) -> None:
    """controller.py rule 3 (a review): the stop owed to a controller that answers again is
    checked at the moving rate as any stop written is: lost again, it goes again within the
    resend time, not an idle poll later (9.8 s on a Rot2Prog)."""
    v = rig("rot2prog")
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    stop = v.cfg.spec.codec_factory().encode_stop()
    stop = stop[0] if isinstance(stop, list) else stop
    v.target(300.0)
    v.run_until(lambda h: h.truth().is_moving, 10, "moving")
    v.run_for(1)
    v.set_deaf(True)
    v.run_for(0.2)
    v.stop()
    v.run_until(lambda h: not h.status.available, 60, "offline")
    v.drop_writes(stop)  # the owed stop, lost again
    v.set_deaf(False)
    t0 = v.now
    v.run_until(lambda h: h.status.available, 60, "online again")
    owed_t = next(w.t for w in v.writes if w.t >= t0 and w.data == stop)
    v.run_until(lambda h: any(w.t > owed_t and w.data == stop for w in h.writes), 60, "again")
    again_t = next(w.t for w in v.writes if w.t > owed_t and w.data == stop)
    assert again_t - owed_t <= v.cfg.motion.stop_resend_s + 1.0, (owed_t, again_t)


def online(rig: Rig, model: str = "gs232b") -> VirtualRotator:
    v = rig(model)
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    return v


def test_a_released_locks_stop_owed_to_a_port_failure_stays_released(rig: Rig) -> None:
    """As test_the_locks_stop_resent_after_silence_is_let_go_as_released, but the USB adapter
    resets (1.5 s after the release: past STOP_UNSURE_S) before the silence is found."""
    v = online(rig)
    locked_and_released_unheard(v)
    v.run_for(1.5)
    v.link_down("USB adapter reset")
    v.set_silent(False)
    v.run_for(1.0)
    v.link_up()
    v.run_until(lambda h: h.status.available and h.state is IDLE, 60, "online")
    not_stopped_by_hand_later(v)


def test_a_released_locks_stop_stays_released_over_two_silences(rig: Rig) -> None:
    """The released lock's stop owed to a silence goes when the controller answers; it answers
    once and is silent again: the stop owed the second time is still the released lock's."""
    v = online(rig)
    locked_and_released_unheard(v)
    v.run_until(lambda h: not h.status.available, 30, "offline")
    v.set_silent(False)
    v.run_until(lambda h: h.status.available, 30, "answers once")
    v.set_silent(True)
    v.run_until(lambda h: not h.status.available, 30, "offline again")
    v.set_silent(False)
    v.run_until(lambda h: h.status.available and h.state is IDLE, 60, "online")
    not_stopped_by_hand_later(v)


def test_a_dcu1s_released_lock_owes_no_stop_to_a_port_reset_an_hour_later(rig: Rig) -> None:
    """A DCU-1 gives no reading: nothing ever clears ``unseen_t``. Lock ON, lock OFF (the tower
    work over), an hour later the operator turns the rotor at the panel and the USB adapter
    resets: the lock's stop, long released, is written twice on the reopen and stops the turn."""
    v = rig("dcu1", emulator={"start_az_deg": 30})
    v.run_for(100)
    v.lock(True)
    v.run_for(1)
    v.lock(False)
    v.run_for(3600)
    v.manual_rotate(300.0)
    v.run_for(1)
    t = v.now
    adapter_reset(v)
    v.run_for(60)
    assert b"AS1;" not in v.sent(since=t), v.sent(since=t)
    assert abs(v.truth().az_deg - 300.0) < 3, v.truth()


def test_a_stop_an_hour_old_is_not_owed_to_a_port_reset_of_a_controller_that_reads(
    rig: Rig,
) -> None:
    """Control: a GS-232B's stop an hour old is seen taken: the reopen owes nothing."""
    v = online(rig)
    v.stop()
    v.run_for(3600)
    t = v.now
    adapter_reset(v)
    v.run_for(10)
    assert b"S\r" not in v.sent(since=t), v.sent(since=t)


def test_a_stop_written_at_time_zero_is_cleared_by_readings_at_rest(rig: Rig) -> None:
    """``now > (unseen_t or now)``: a stop written at 0.0 (a locked start, virtual time) is
    falsy and never cleared; every later port failure owes it."""
    v = rig("gs232b", locked=True)
    v.run_for(3600)
    assert v.session.controller.stops.unseen_t is None


def test_a_lock_on_while_found_silent_is_checked_as_the_new_locks(rig: Rig) -> None:
    """Lock ON, OFF, the controller's replies lost: found silent, the released lock's stop is
    owed as released. Still offline (the port open), the operator locks again for tower work:
    that lock's stop is written, but the owed one keeps ``_released_owed``, goes as released
    when it answers, and is let go: a turn at the panel during the tower work runs on."""
    v = online(rig)
    locked_and_released_unheard(v)
    v.run_until(lambda h: not h.status.available, 30, "offline")
    v.lock(True)  # tower work again
    v.run_for(1.0)
    v.set_silent(False)
    v.run_until(lambda h: h.status.available and h.state is IDLE, 60, "online")
    v.run_for(60.0)
    t = v.now
    v.manual_rotate(300.0)
    v.run_for(60.0)
    assert v.status.locked
    assert b"S\r" in v.sent(since=t) and abs(v.truth().az_deg - 300.0) > 5, v.truth()


def stamped_behind_a_lane_stop(v: VirtualRotator, expiry_s: float) -> float:
    """The lane's stop with its hold 1, then a stamped target to 300 read after its copy
    (interfaces/mqtt/service.py rule 9: its expiry ``expiry_s`` from now, on the steady clock):
    it waits for the marker (session.py rule 13). The time it was put."""
    t = v.now
    v.mailbox.put(Stop(Source.MQTT), hold=1)
    v.mailbox.put(Target(300.0, not_after_s=t + expiry_s))
    v._take()
    return t


@pytest.mark.parametrize(("back_s", "goes"), [(8.0, False), (2.0, True)])
def test_a_stamped_target_held_past_its_expiry_is_dropped_when_the_hold_ends(
    rig: Rig, back_s: float, goes: bool
) -> None:
    """Review 25, R25-3: the marker back after the target's 5 s expiry: dropped, said; back
    within it: it goes."""
    v = ready(rig)
    t = stamped_behind_a_lane_stop(v, 5.0)
    v.run_for(back_s)
    assert bearings(v, since=t) == []
    v.mailbox.put_release(1)
    v._take()
    if goes:
        v.run_until(lambda h: h.state is IDLE and abs(h.truth().az_deg - 300) < 4, 120, "at 300")
        assert bearings(v, since=t) == [b"AP1300\r"]
        assert not [e for e in v.errors(since=t) if "expiry" in e.message]
    else:
        v.run_for(30)
        assert bearings(v, since=t) == [] and not v.truth().is_moving
        said = [e.message for e in v.errors(since=t)]
        assert any("expiry passed while it waited" in m for m in said), said


def test_a_stamped_target_taken_after_its_expiry_is_dropped(rig: Rig) -> None:
    """One taken from the mailbox already past its expiry (a move lastword.py rule 13 kept
    behind a lock OFF and put at the marker) never goes."""
    v = ready(rig)
    t = v.now
    v.mailbox.put(Target(300.0, not_after_s=t - 0.5))
    v._take()
    v.run_for(30)
    assert bearings(v, since=t) == []
    said = [e.message for e in v.errors(since=t)]
    assert any("expiry passed" in m for m in said), said


def test_a_stamped_target_taken_in_time_still_waits_out_the_controllers_own_rules(
    rig: Rig,
) -> None:
    """Taken in time, a stamped target is the bridge's to carry out: a Rotor-EZ turning must
    stop and brake first (motion.py), longer than its expiry, and it still goes."""
    v = ready(rig)
    v.target(200)
    v.run_until(lambda h: h.truth().is_moving, 10, "turning")
    t = v.now
    v.mailbox.put(Target(60.0, not_after_s=t + 0.5))
    v._take()
    v.run_until(lambda h: h.state is IDLE and abs(h.truth().az_deg - 60) < 4, 120, "at 60")
    assert bearings(v, since=t)[-1:] == [b"AP1060\r"]
    assert not [e for e in v.errors(since=t) if "expiry" in e.message]
    sent = [f.time_s for f in v.frames(*BEARING_OUTCOMES, since=t)][-1]
    assert sent - t > 0.5  # (it went after its expiry: the stop and brake came first)


# Rule 13 for a stamped start (core/model.py ``Move``): a track or follow start and a feature's
# own command that moves carry their expiry as a target does (review 34: a track start read
# after a lane STOP's copy waited for the marker, back 14 s later, and tracking turned the
# rotor). A station where the sun is up for tracking, WSJT-X heard for following, and the toy
# feature of test_feature_commands.py whose ``aim`` turns the rotor.
STARTS = ("track", "follow", "beam")


def starts_rig(rig: Rig, monkeypatch: pytest.MonkeyPatch) -> VirtualRotator:
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, TOY))
    lat, lon = sun_up_somewhere(SUN_EPOCH)
    return ready(rig, sky=Sky(lat, lon), wall_epoch_s=SUN_EPOCH, follow=FOLLOWING)


def iss_tle(v: VirtualRotator, tmp_path: Path) -> Path:
    """A TLE file naming one satellite, ISS (ZARYA), for a look-up by name."""
    path = tmp_path / "amateur.tle"
    line1, line2 = synthetic_tle("", v.wall(), inclination_deg=51.6, raan_deg=0, mean_anomaly_deg=0)
    path.write_text(f"ISS (ZARYA)\n{line1}\n{line2}\n")
    return path


def put_start(v: VirtualRotator, kind: str, not_after_s: float) -> None:
    """A stamped start of ``kind`` put as the judge puts it (runtime/rotator.py), with what makes
    it turn the rotor (WSJT-X naming a partner far from where the rotor points)."""
    if kind == "track":
        v.mailbox.put_track(Track(Body.sun(), described="track sun", not_after_s=not_after_s))
    elif kind == "follow":
        v.mailbox.put_follow(Follow(True, described="follow", not_after_s=not_after_s))
        v.mailbox.put_heard(Heard("JA1ABC", "PM95", False))
    else:
        aim = FeatureCommand(feature="beam", name="aim", value=200.0, not_after_s=not_after_s)
        v.mailbox.put_feature(aim)


@pytest.mark.parametrize("kind", STARTS)
@pytest.mark.parametrize(("back_s", "goes"), [(8.0, False), (2.0, True)])
def test_a_stamped_start_held_past_its_expiry_turns_nothing_when_the_hold_ends(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, kind: str, back_s: float, goes: bool
) -> None:
    """Review 34: the marker back after the start's 5 s expiry: what it began (tracking,
    following, the part's motion) ends, said, and the rotor stays where it is; back within it:
    the rotor turns."""
    v = starts_rig(rig, monkeypatch)
    t = v.now
    v.mailbox.put(Stop(Source.MQTT), hold=1)
    put_start(v, kind, t + 5.0)
    v._take()
    v.run_for(back_s)
    assert bearings(v, since=t) == []
    v.mailbox.put_release(1)
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    if goes:
        assert bearings(v, since=t) != [], said
        assert not [m for m in said if "expiry" in m], said
    else:
        assert bearings(v, since=t) == [] and not v.truth().is_moving, said
        assert any("expiry passed" in m for m in said), said
        assert v.status.tracking is None and v.status.following is None


@pytest.mark.parametrize("kind", STARTS)
def test_a_stamped_start_taken_after_its_expiry_is_refused(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, kind: str
) -> None:
    """One taken from the mailbox already past its expiry (kept behind a lock OFF and put at
    its marker: lastword.py rule 13) starts nothing."""
    v = starts_rig(rig, monkeypatch)
    t = v.now
    put_start(v, kind, t - 0.5)
    v._take()
    v.run_for(30)
    assert bearings(v, since=t) == [] and not v.truth().is_moving
    said = [e.message for e in v.errors(since=t)]
    assert any("expiry passed" in m for m in said), said
    assert v.status.tracking is None and v.status.following is None


def test_a_later_start_under_the_hold_takes_the_place_of_a_stamped_one(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A stamped track start, then an unstamped follow start under the same hold (it ends
    tracking): the marker back past the track's expiry ends nothing of the follow's."""
    v = starts_rig(rig, monkeypatch)
    t = v.now
    v.mailbox.put(Stop(Source.MQTT), hold=1)
    put_start(v, "track", t + 5.0)
    v._take()
    v.mailbox.put_follow(Follow(True, described="follow"))
    v.mailbox.put_heard(Heard("JA1ABC", "PM95", False))
    v._take()
    v.run_for(8.0)
    v.mailbox.put_release(1)
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert bearings(v, since=t) != [] and not [m for m in said if "expiry" in m], said
    assert v.status.following is not None
