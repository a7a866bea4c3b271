"""The motion state machine, driven by a fake clock: no sleeps."""

from __future__ import annotations

from dataclasses import replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bridge.core.model import MotionState as S
from bridge.core.model import RotatorStatus
from bridge.protocols import REGISTRY
from bridge.session import motion as mo
from bridge.session.status import WAY_UNKNOWN, publishable_bearing, worth_emitting

CFG = mo.MotionConfig(
    REGISTRY["rotorez"], tolerance_deg=3, stall_timeout_s=8, brake_delay_s=5, settle_s=1.5,
    noise_deg=2,
)  # fmt: skip
DCU = mo.MotionConfig(REGISTRY["dcu1"], brake_delay_s=5, nominal_speed_deg_s=6)


def feed(m: mo.Motion, readings: list[tuple[float, float]], cfg: mo.MotionConfig = CFG):
    events: list[mo.Event] = []
    for t, az in readings:
        m, ev = mo.reading(m, cfg, az, t)
        events += ev
    return m, events


def still(m: mo.Motion, t: float, cfg: mo.MotionConfig = CFG) -> tuple[mo.Motion, list[mo.Event]]:
    """A reading at ``t`` that finds the rotor where the last one did (rule 2: only a reading
    says it is still)."""
    assert m.position_deg is not None
    return mo.reading(m, cfg, m.position_deg, t, m.el_position_deg)


def ready(at: float = 0.0, az: float = 100.0) -> mo.Motion:
    m = mo.link_up(mo.Motion(), CFG, at)
    m, _ = mo.reading(m, CFG, az, at)
    m, _ = mo.tick(m, CFG, at + CFG.brake_delay_s)
    assert m.state is S.IDLE
    return m


def test_first_reading_assumes_a_brake_window_then_idle() -> None:
    m = mo.link_up(mo.Motion(), CFG, 0)
    assert m.state is S.OFFLINE
    m, _ = mo.reading(m, CFG, 100, 0.0)
    assert m.state is S.BRAKING
    assert mo.plan_target(m, CFG, 1.0) is mo.Plan.WAIT
    m, _ = mo.tick(m, CFG, 4.9)
    assert m.state is S.BRAKING
    m, _ = mo.tick(m, CFG, 5.0)
    assert m.state is S.IDLE and mo.plan_target(m, CFG, 5.0) is mo.Plan.SEND


def test_jitter_at_rest_is_not_motion() -> None:
    m = ready()
    m, events = feed(m, [(10 + i * 0.25, 100 + (i % 2) * 2) for i in range(40)])
    assert m.state is S.IDLE and events == []


def test_commanded_move_arrives_then_brakes_then_idles() -> None:
    m = mo.commanded(ready(), CFG, 120, 10.0)
    assert m.state is S.MOVING and m.target_deg == 120
    readings = [(10 + i * 0.25, min(100 + 1.5 * i, 121)) for i in range(1, 20)]
    m, events = feed(m, readings)
    assert m.state is S.MOVING  # not yet steady
    last_move_t = m.last_move_t
    assert last_move_t is not None
    m, events = still(m, last_move_t + CFG.settle_s)
    assert events == [mo.Event.ARRIVED] and m.state is S.BRAKING and m.target_deg is None
    assert mo.plan_target(m, CFG, last_move_t + CFG.settle_s) is mo.Plan.WAIT
    # the brake window counts from the last change (plus one poll), not from the detection
    assert m.changed_t is not None
    stopped_t = max(last_move_t, m.changed_t) + CFG.poll_margin_s + mo.BRAKE_GUARD_S
    m, _ = mo.tick(m, CFG, stopped_t + CFG.brake_delay_s - 0.01)
    assert m.state is S.BRAKING
    m, _ = mo.tick(m, CFG, stopped_t + CFG.brake_delay_s)
    assert m.state is S.IDLE


def test_the_clock_alone_never_calls_a_rotor_still() -> None:
    """Rule 2: readings missed (a starved line, lost replies) are no stillness: only a reading
    ``settle_s`` after the last movement says the rotor arrived, or stopped."""
    m = mo.commanded(ready(), CFG, 110, 10.0)
    m, _ = feed(m, [(10.2, 103), (10.4, 106), (10.6, 108)])
    m, events = mo.tick(m, CFG, 10.6 + CFG.settle_s + 1.0)  # (before a stall)
    assert events == [] and m.state is S.MOVING and m.target_deg == 110
    m, events = mo.reading(m, CFG, 110, 10.6 + CFG.settle_s + 1.1)  # it turned on: movement
    assert events == [] and m.state is S.MOVING
    m, events = still(m, 10.6 + CFG.settle_s + 1.1 + CFG.settle_s)
    assert events == [mo.Event.ARRIVED] and m.position_deg == 110
    m, _ = feed(ready(), [(20.0, 103), (20.5, 106)])  # by hand: its stop, the same
    m, events = mo.tick(m, CFG, 30.0)
    assert events == [] and m.state is S.MOVING
    m, events = still(m, 30.0)
    assert events == [mo.Event.STOPPED] and m.state is S.IDLE  # (its brake window: over)


def test_a_rotor_at_its_target_with_its_readings_lost_is_no_stall() -> None:
    """Rule 3: off target, no progress for ``stall_timeout_s`` is a stall; at its target (by the
    last reading) it is the reading that finds it still, when it comes, that says arrived."""
    m = mo.commanded(ready(), CFG, 110, 10.0)
    m, _ = feed(m, [(10.2, 103), (10.4, 106), (10.6, 109)])
    m, events = mo.tick(m, CFG, 10.6 + CFG.stall_timeout_s + 1)
    assert events == [] and m.state is S.MOVING and mo.at_target(m, CFG)
    # a new target: a rotor that may still turn its last degrees is stopped first; one at
    # its target and still by the clock is not (its reading is late): the target waits for it
    assert mo.plan_target(m, CFG, 10.6 + CFG.settle_s - 0.01) is mo.Plan.STOP_FIRST
    assert mo.plan_target(m, CFG, 10.6 + CFG.settle_s) is mo.Plan.WAIT
    assert mo.next_deadline(m, CFG, 10.6) == 10.6 + CFG.settle_s
    m, events = still(m, 10.6 + CFG.stall_timeout_s + 1.1)
    assert events == [mo.Event.ARRIVED]


def test_a_stop_goes_again_only_while_readings_show_the_rotor_turning() -> None:
    """stops.py rule 2 (``stop_again``): from ``stop_resend_s`` after the stop, while a movement
    since it is less than ``settle_s`` old; after that the next reading may find it still."""
    m = mo.stop_sent(mo.commanded(ready(), CFG, 200, 10.0), CFG, 10.5)
    m, _ = feed(m, [(11.0, 104)])  # where the stop found it: no proof it turned on
    assert not mo.stop_again(m, CFG, 10.5 + CFG.stop_resend_s)
    m, _ = feed(m, [(11.5, 108), (12.0, 112)])
    late = 10.5 + CFG.stop_resend_s
    assert not mo.stop_again(m, CFG, late - 0.01)
    assert mo.stop_again(m, CFG, late) and mo.plan_target(m, CFG, late) is mo.Plan.STOP_FIRST
    assert mo.stop_again(m, CFG, 12.0 + CFG.settle_s - 0.01)
    assert not mo.stop_again(m, CFG, 12.0 + CFG.settle_s)  # (readings lost since: no proof)
    assert mo.plan_target(m, CFG, 12.0 + CFG.settle_s) is mo.Plan.WAIT
    assert mo.next_deadline(m, CFG, late) == 12.0 + CFG.settle_s
    # a stop owed on connect: the connection's first reading is the first after it (a last
    # read: it was not, and the repeat waited a reading more)
    m = mo.stop_sent(mo.link_up(mo.Motion(), CFG, 0.0), CFG, 0.0)
    m, _ = mo.reading(m, CFG, 100, 0.2)
    assert m.stop_read_t == 0.2


def test_a_rotor_running_on_after_a_stop_is_not_stopped_again() -> None:
    """stops.py rule 2 (``coast_end``): readings that show the rotor run on with its motor
    off, up to a second and a moving poll after the stop, send no second stop; a movement
    read after that, at ``stop_resend_s``, does, as it always did."""
    m = mo.stop_sent(mo.commanded(ready(), CFG, 200, 10.0), CFG, 10.5)
    coasted, _ = feed(m, [(10.6, 104), (10.8, 105), (11.0, 105.5), (11.2, 106), (11.4, 106)])
    end = mo.coast_end(CFG, 10.5)
    assert 11.2 < end <= 10.5 + CFG.stop_resend_s
    for now in (10.5 + CFG.stop_resend_s, 11.2 + CFG.settle_s - 0.01):
        assert not mo.stop_again(coasted, CFG, now)
        assert mo.plan_target(coasted, CFG, now) is mo.Plan.WAIT
    # the same readings and one more, read after the coast: still turning, stopped again
    turning, _ = feed(coasted, [(end, 107)])
    assert mo.stop_again(turning, CFG, 10.5 + CFG.stop_resend_s)
    # a moving poll so slow that the coast would reach past the resend: the resend's time
    slow = replace(CFG, poll_margin_s=3.0)
    assert mo.coast_end(slow, 10.5) == 10.5 + CFG.stop_resend_s


def test_a_target_after_an_arrival_waits_only_for_the_brake() -> None:
    """A preset pressed 1.2 s after the arrival: the brake delay runs from the stop itself."""
    m = mo.commanded(ready(), CFG, 110, 10.0)
    m, _ = feed(m, [(10.2, 103), (10.4, 106), (10.6, 109), (10.8, 110), (11.0, 110)])
    m, events = still(m, 10.6 + CFG.settle_s)
    assert events == [mo.Event.ARRIVED]
    m, _ = mo.tick(m, CFG, 10.6 + CFG.settle_s + 1.2)
    assert mo.plan_target(m, CFG, 13.3) is mo.Plan.WAIT
    # the last change (109 -> 110 at 10.8), one poll, the guard: 16.3, not 17.1
    stopped_t = 10.8 + CFG.poll_margin_s + mo.BRAKE_GUARD_S
    m, _ = mo.tick(m, CFG, stopped_t + CFG.brake_delay_s - 0.01)
    assert mo.plan_target(m, CFG, stopped_t + CFG.brake_delay_s - 0.01) is mo.Plan.WAIT
    m, _ = mo.tick(m, CFG, stopped_t + CFG.brake_delay_s)
    assert mo.plan_target(m, CFG, stopped_t + CFG.brake_delay_s) is mo.Plan.SEND


def test_manual_rotation_shows_as_moving() -> None:
    m = ready()
    m, _ = feed(m, [(20.0, 103), (20.5, 106), (21.0, 109)])
    assert m.state is S.MOVING and m.target_deg is None
    m, events = still(m, 22.5)
    assert events == [mo.Event.STOPPED] and m.state is S.BRAKING


def test_no_progress_while_off_target_is_a_stall() -> None:
    m = mo.commanded(ready(), CFG, 200, 10.0)
    m, events = feed(m, [(10 + i * 0.5, 100 + (i % 2)) for i in range(1, 16)])
    assert m.state is S.MOVING and events == []
    m, events = mo.tick(m, CFG, 18.0)
    assert events == [mo.Event.STALLED] and m.state is S.STALLED and m.target_deg is None
    assert mo.plan_target(m, CFG, 19.0) is mo.Plan.WAIT  # the controller's brake delay
    assert mo.plan_target(m, CFG, 23.0) is mo.Plan.SEND


def test_retarget_while_turning_is_stop_then_wait_for_stillness_and_brake() -> None:
    m = mo.commanded(ready(), CFG, 200, 10.0)
    m, _ = feed(m, [(10.5, 103), (11.0, 106)])
    assert mo.plan_target(m, CFG, 11.0) is mo.Plan.STOP_FIRST
    m = mo.stop_sent(m, CFG, 11.0)
    assert mo.plan_target(m, CFG, 11.1) is mo.Plan.WAIT
    m, events = feed(m, [(11.25, 107), (11.5, 107), (12.0, 108)])
    assert m.state is S.MOVING  # stopping, not yet steady for settle_s
    m, events = still(m, 12.5)  # 1.5 s after the last movement
    assert events == [mo.Event.STOPPED] and m.state is S.BRAKING
    assert mo.plan_target(m, CFG, 17.4) is mo.Plan.WAIT
    m, _ = mo.tick(m, CFG, 17.5)
    assert mo.plan_target(m, CFG, 17.5) is mo.Plan.SEND


def test_stop_is_resent_if_the_rotor_keeps_turning() -> None:
    m = mo.commanded(ready(), CFG, 200, 10.0)
    m = mo.stop_sent(m, CFG, 10.5)
    m, _ = feed(m, [(11.0, 104), (11.5, 108), (12.0, 112), (12.5, 116)])
    assert mo.plan_target(m, CFG, 12.0) is mo.Plan.WAIT
    assert mo.plan_target(m, CFG, 12.5) is mo.Plan.STOP_FIRST


def test_no_second_stop_without_a_reading_that_shows_the_first_did_not_take() -> None:
    """A controller silent while it moves (SatEL): no reading since the stop is no evidence
    that the rotor still turns; the target waits for the reading instead of stopping again."""
    m = mo.commanded(ready(), CFG, 200, 10.0)
    m = mo.stop_sent(m, CFG, 10.5)
    assert mo.plan_target(m, CFG, 20.0) is mo.Plan.WAIT


def test_wrap_at_north_counts_as_near() -> None:
    assert mo.angle_error(359, 1, wraps=True) == 2
    assert mo.angle_error(359, 1, wraps=False) == 358
    m = mo.commanded(ready(az=358), CFG, 0, 10.0)
    m, _ = feed(m, [(10.5, 359), (11.0, 360)])
    m, events = still(m, 13.0)
    assert events == [mo.Event.ARRIVED]


def test_dcu1_without_feedback_is_unknown_and_assumes_travel_time() -> None:
    m = mo.link_up(mo.Motion(), DCU, 0.0)
    assert m.state is S.UNKNOWN
    # at start it might still be turning: stop first, then the brake delay
    assert mo.plan_target(m, DCU, 1.0) is mo.Plan.STOP_FIRST
    m = mo.stop_sent(m, DCU, 1.0)
    assert mo.plan_target(m, DCU, 6.0) is mo.Plan.WAIT  # the brake timer starts a hair late
    assert mo.plan_target(m, DCU, 6.0 + mo.BRAKE_GUARD_S) is mo.Plan.SEND
    m = mo.commanded(m, DCU, 90.0, 6.0)
    assert m.state is S.UNKNOWN and m.target_deg == 90
    assert mo.plan_target(m, DCU, 7.0) is mo.Plan.STOP_FIRST
    # a stop leaves the position unknown: the next move is assumed to take the whole range
    assert mo.commanded(mo.stop_sent(m, DCU, 7.0), DCU, 120.0, 12.0).busy_until_t == 104.0
    # once the 90 move is assumed done, 90 -> 120 is 1.5 * 30 / 6 + 2 = 9.5 s of travel
    assert mo.plan_target(m, DCU, 200.0) is mo.Plan.SEND
    m = mo.commanded(m, DCU, 120.0, 12.0)
    assert m.busy_until_t == 12.0 + 9.5
    assert mo.plan_target(m, DCU, 21.6) is mo.Plan.WAIT  # brake delay after the assumed arrival
    assert mo.plan_target(m, DCU, 26.5) is mo.Plan.SEND
    m, _ = mo.tick(m, DCU, 26.5)
    assert m.target_deg is None


def test_deadband_holds_the_published_bearing_at_rest() -> None:
    pb = publishable_bearing
    assert pb(None, 0, 100, False, 2, True) == (100, 0)
    assert pb(100, 0, 101, False, 2, True) == (None, 0)
    assert pb(100, 0, 102, False, 2, True) == (None, 0)
    assert pb(100, 0, 103, False, 2, True) == (103, 1)
    assert pb(1, 0, 359, False, 2, True) == (None, 0)  # 2 degrees across north
    assert pb(2, 0, 358, False, 2, True) == (358, -1)


def test_while_moving_progress_is_published_and_jitter_back_is_not() -> None:
    pb = publishable_bearing
    published, direction, shown = 100.0, 0, []
    for reading in [101, 102, 103, 104, 105, 120, 121, 120, 121, 120, 121]:
        new, direction = pb(published, direction, reading, True, 2, True)
        if new is not None:
            published = new
            shown.append(new)
    assert shown == [101, 102, 103, 104, 105, 120, 121]


def test_the_last_degrees_of_a_turn_are_published_as_it_comes_to_rest() -> None:
    """status.py rule 1: coasting (the reading that found it still, its brake window), a step
    on the way it turned is published inside the deadband; a step back is not, nor a step
    with no way known (after a reconnect)."""
    pb = publishable_bearing
    assert pb(58, 1, 60, False, 2, True, coasting=True) == (60, 1)
    assert pb(58, 1, 60, False, 2, True) == (None, 1)  # at rest: the deadband
    assert pb(58, 1, 57, False, 2, True, coasting=True) == (None, 1)  # back: jitter
    assert pb(58, 0, 60, False, 2, True, coasting=True) == (None, 0)  # no way known
    assert pb(359, 1, 1, False, 2, True, coasting=True) == (1, 1)  # on across north


def test_a_long_turn_read_at_its_ends_alone_keeps_the_way_it_went() -> None:
    """status.py rule 1 on a busy machine (the demo's park ended at 1, not 0): a RotorCard
    (its travel ends at north) parked from 290 was read at 290, then at its park, 0 (its polls
    late); the shorter way round called that +70, and the jitter at rest, 1, was shown as the
    turn's last degree for good. Towards its target it went down the scale: 1 is jitter back."""
    pb = publishable_bearing
    published, direction = pb(290, -1, 0, True, 2, True, toward=0)
    assert (published, direction) == (0, WAY_UNKNOWN)  # (there: the way it came is not known)
    for moving, coasting in ((True, False), (False, True)):  # jitter, not its last degree
        assert pb(0, WAY_UNKNOWN, 1, moving, 2, True, coasting) == (None, WAY_UNKNOWN)
    assert pb(0, -1, 1, True, 2, True, toward=0) == (None, -1)  # jitter back, moving or not
    assert pb(0, -1, 1, False, 2, True, coasting=True) == (None, -1)
    assert pb(290, -1, 0, True, 2, True) == (0, 1)  # (no target known: the shorter way)
    # its other end: the 360 a Rotor-EZ family board reads as 000, reached from 350
    assert pb(350, 1, 0, True, 2, True, toward=360) == (0, 1)
    assert pb(0, 1, 359, True, 2, True, toward=360) == (None, 1)


def test_next_deadline_is_in_the_future() -> None:
    m = mo.commanded(ready(), CFG, 200, 10.0)  # (an arrival comes with a reading: rule 2)
    assert mo.next_deadline(m, CFG, 10.0) == 10.0 + CFG.stall_timeout_s
    m, _ = mo.tick(m, CFG, 30.0)
    assert m.state is S.STALLED
    assert mo.next_deadline(m, CFG, 30.0) == 35.0
    assert mo.next_deadline(m, CFG, 36.0) is None


def test_the_long_way_round_is_progress_not_a_stall() -> None:
    # 10 -> 350 on a rotor with its stop at 0/360: it first moves away from 350 across north
    m = mo.commanded(ready(az=10), CFG, 350, 10.0)
    readings = [(10 + i * 0.25, 10 + 1.5 * i) for i in range(1, 240)]
    m, events = feed(m, [(t, az) for t, az in readings if az <= 351])
    assert mo.Event.STALLED not in events
    m, events = still(m, 70.0)
    assert mo.Event.ARRIVED in events


def test_without_a_brake_the_first_reading_still_waits_for_stillness() -> None:
    """No brake, never braking (rule 4): idle at once, but settling: no target yet."""
    card = mo.MotionConfig(REGISTRY["rotorcard"], brake_delay_s=0, settle_s=1.5, noise_deg=2)
    m = mo.link_up(mo.Motion(), card, 0.0)
    m, _ = mo.reading(m, card, 100, 0.0)
    assert m.state is S.IDLE and mo.settling(m)
    assert mo.plan_target(m, card, 0.5) is mo.Plan.WAIT
    m, _ = mo.reading(m, card, 104, 0.5)  # it was turning when we connected
    assert m.state is S.MOVING and mo.plan_target(m, card, 0.5) is mo.Plan.STOP_FIRST
    m2 = mo.link_up(mo.Motion(), card, 0.0)
    m2, _ = mo.reading(m2, card, 100, 0.0)
    assert mo.next_deadline(m2, card, 0.0) == 1.5
    m2, _ = mo.tick(m2, card, 1.5)
    assert m2.state is S.IDLE and not mo.settling(m2)
    assert mo.plan_target(m2, card, 1.5) is mo.Plan.SEND


def test_after_lost_readings_the_next_one_is_taken_like_the_first() -> None:
    """A lost after-move report: the jump to the next reading is no movement after the stop
    (no second stop), and the rotor is idle only after settle_s of stillness."""
    m = mo.stop_sent(mo.commanded(ready(), CFG, 200, 10.0), CFG, 30.0)
    m = mo.track_lost(m, CFG)
    assert m.state is S.BRAKING and m.target_deg is None and m.stop_sent_t is None
    m, events = mo.reading(m, CFG, 200, 32.0)
    assert events == [] and m.state is S.BRAKING
    assert mo.plan_target(m, CFG, 32.0) is mo.Plan.WAIT
    m, _ = mo.reading(m, CFG, 200, 33.5)
    m, _ = mo.tick(m, CFG, 37.0)  # settled, and the brake delay is over
    assert m.state is S.IDLE and m.position_deg == 200


def test_a_slew_that_ended_unseen_is_no_stall_and_the_next_reading_decides() -> None:
    """A SatEL slew of 20 s (longer than the stall timeout) ends with a report that cannot be
    read: without readings during it, that is no stall. The reading asked for at once shows
    the rotor at the target: arrived after the settle window."""
    m = mo.commanded(ready(), CFG, 200, 10.0)
    m = mo.slew_ended(m, 30.0)
    m, events = mo.tick(m, CFG, 30.0)
    assert events == [] and m.state is S.MOVING
    m, events = mo.reading(m, CFG, 200, 30.2)
    m, events2 = still(m, 31.8)
    assert events + events2 == [mo.Event.ARRIVED]
    # without the hook the same tick is a stall: the test above is not vacuous
    _, events = mo.tick(mo.commanded(ready(), CFG, 200, 10.0), CFG, 30.0)
    assert events == [mo.Event.STALLED]
    # and a rotor the slew left short of its target stalls only a whole timeout later
    m = mo.slew_ended(mo.commanded(ready(), CFG, 200, 10.0), 30.0)
    m, _ = mo.reading(m, CFG, 150, 30.2)
    assert mo.tick(m, CFG, 38.0)[1] == [] and mo.tick(m, CFG, 38.3)[1] == [mo.Event.STALLED]


SPID = mo.MotionConfig(
    REGISTRY["rot2prog"], tolerance_deg=3, stall_timeout_s=8, brake_delay_s=0, settle_s=1.5,
    noise_deg=2,
)  # fmt: skip


def spid_moving_to(target: float, tolerance: float = 3) -> mo.Motion:
    cfg = replace(SPID, tolerance_deg=tolerance)
    m = mo.link_up(mo.Motion(), cfg, 0)
    m, _ = mo.reading(m, cfg, 100, 0.0)
    m, _ = mo.tick(m, cfg, 2.0)
    return mo.commanded(m, cfg, target, 10.0)


def test_a_spid_turned_away_from_its_target_is_the_front_panel_and_loses_the_target() -> None:
    """Rule 5: a SPID heads straight for its raw target, so readings growing away from it are
    someone else's hand. Before, the target was held until a stall 10 s after the hand let go,
    and tracking pulled the rotor back in between."""
    m = spid_moving_to(120)
    m, events = feed(m, [(10.5, 104), (11.0, 108), (11.5, 103), (12.0, 99)], SPID)
    assert events == [] and m.target_deg == 120  # within tolerance + noise + margin
    m, events = feed(m, [(12.5, 96.5)], SPID)
    assert events == [] and m.target_deg == 120  # away once
    m, events = feed(m, [(13.0, 94)], SPID)
    assert events == [mo.Event.TURNED_AWAY]
    assert m.state is S.MOVING and m.target_deg is None  # nothing is sent: the hand has it
    m, events = feed(m, [(13.5, 92.0), (14.0, 92.0)], SPID)
    m, events = still(m, 16.0, SPID)
    assert events == [mo.Event.STOPPED]


def test_a_rotor_that_turns_on_past_its_target_passed_it() -> None:
    """Rule 5: a rotor that came to its target and turns on away from it is heading elsewhere
    (the target frame lost on the line, the rotor still on its way to the bearing before):
    ``passed``, on a scale that wraps as on one that does not."""
    m = spid_moving_to(120)
    m, events = feed(m, [(10.5, 106), (11.0, 112), (11.5, 118), (12.0, 119.5)], SPID)
    assert events == [] and m.target_deg == 120  # on its way: never away
    m, events = feed(m, [(12.5, 122.5), (13.0, 125.0), (13.5, 127.5), (14.0, 131.0)], SPID)
    assert events == [] and m.target_deg == 120  # within tolerance + noise + margin, or once
    m, events = feed(m, [(14.5, 133.5)], SPID)
    assert events == [mo.Event.PASSED] and m.target_deg is None
    # a Rotor-EZ over north to 10: it reads 6 and 14 either side of it (never within 3)
    m = mo.commanded(ready(az=330), CFG, 10, 10.0)
    readings = [(10 + 0.5 * i, (330 + 8.0 * i) % 360) for i in range(1, 12)]
    m, events = feed(m, readings[:6])
    assert events == [] and m.target_deg == 10  # 338 .. 18: over it between 2 and 18
    m, events = feed(m, readings[6:])
    assert events == [mo.Event.PASSED] and m.target_deg is None, readings


HELD = mo.MotionConfig(
    REGISTRY["gs232b"], tolerance_deg=3, stall_timeout_s=8, brake_delay_s=0, settle_s=1.5,
    noise_deg=2, el_limits_deg=(0.0, 90.0),
)  # fmt: skip


def held_moving_to(el_from: float, el_target: float, az: float = 100.0) -> mo.Motion:
    m = mo.link_up(mo.Motion(), HELD, 0)
    m, _ = mo.reading(m, HELD, az, 0.0, el_from)
    m, _ = mo.tick(m, HELD, 2.0)
    return mo.commanded(m, HELD, az, 10.0, el_target)


def feed_el(m: mo.Motion, els: list[float], t0: float = 10.0, cfg: mo.MotionConfig = HELD):
    events: list[mo.Event] = []
    for i, el in enumerate(els, 1):
        assert m.position_deg is not None
        m, ev = mo.reading(m, cfg, m.position_deg, t0 + 0.5 * i, el)
        events += ev
    return m, events


def test_an_elevation_turning_on_past_its_limit_is_stopped_there() -> None:
    """Rule 10 (an attack pass: a GS-232 target frame one flipped bit from ``U``, up until
    stopped, ran an elevation held to 90 degrees to 103, told only by a pass 10 degrees beyond
    its target): two readings in a row more than ``tolerance_deg + noise_deg`` past the limit,
    the second further out and a movement, drop the target and tell ``past limit``; which
    axis, its reading and limit are in ``Motion.past``."""
    m = held_moving_to(80, 89)
    m, events = feed_el(m, [81, 83, 85, 87, 89, 91, 93, 95, 96])
    assert events == [] and m.el_target_deg == 89  # once, or within the margin
    m, events = feed_el(m, [98], 15.0)
    assert events[:1] == [mo.Event.PAST_LIMIT] and m.target_deg is m.el_target_deg is None
    assert m.past == ("elevation", 98, 90.0, "el_max_deg")
    # below the horizon the same, and on a scale that does not wrap the azimuth too
    m, events = feed_el(held_moving_to(10, 2), [8, 5, 2, -1, -4, -6, -8])
    assert events[:1] == [mo.Event.PAST_LIMIT], events
    assert m.past == ("elevation", -8, 0.0, "el_min_deg")
    spid = replace(SPID, az_limits_deg=(-180.0, 200.0))
    m = mo.commanded(spid_moving_to(120), spid, 190, 10.0)
    m, events = feed(m, [(10.5, 180), (11.0, 190), (11.5, 200), (12.0, 206), (12.5, 209)], spid)
    assert events[:1] == [mo.Event.PAST_LIMIT] and m.past == ("azimuth", 209, 200, "az_max_deg")
    assert mo.commanded(m, spid, 190, 13.0).past is None  # (a new target's turn: none yet)


def test_one_corrupt_reading_or_a_coast_past_a_limit_is_no_limit_crossed() -> None:
    """Rule 10, a review: one reply with a digit flipped (86 read 96) past the limit stopped
    the rotor short of its target, 89, and ended tracking; and a turn to a target at the
    limit that coasts a little past it (within the tolerance arrival allows) is no crossing."""
    m, events = feed_el(held_moving_to(60, 89), [70, 80, 96, 87, 89, 89, 89, 89, 89])
    assert events == [mo.Event.ARRIVED] and m.past is None
    m, events = feed_el(held_moving_to(60, 90), [70, 80, 88, 91, 93, 93, 93, 93, 93])
    assert events == [mo.Event.ARRIVED] and m.past is None


def test_a_rotor_outside_a_limit_brought_back_or_jittering_there_is_no_limit_crossed() -> None:
    """Rule 10: a rotor a narrower limit leaves outside (or a hand turned there) moves inward
    to a target inside; its jitter out there, with the azimuth turning, is no movement of
    the elevation; and a wrapping azimuth is never judged (its controller picks its way)."""
    m = held_moving_to(97, 60, az=100)
    m = mo.commanded(m, HELD, 200, 10.0, 60)  # the azimuth turns, the elevation jitters
    readings = [(106, 98), (112, 97), (118, 99), (124, 98), (130, 99)]
    events: list[mo.Event] = []
    for i, (az, el) in enumerate(readings, 1):
        m, ev = mo.reading(m, HELD, az, 10 + 0.5 * i, el)
        events += ev
    assert events == [] and m.el_target_deg == 60
    m, events = feed_el(m, [95, 92, 89, 85], 13.0)
    assert events == [] and m.el_target_deg == 60
    wrapping = replace(CFG, az_limits_deg=(20.0, 340.0))
    m = mo.commanded(ready(az=330), wrapping, 10, 10.0)  # the long way round a stop at north
    m, events = feed(m, [(10.5, 334), (11.0, 338), (11.5, 342), (12.0, 346), (12.5, 350)], wrapping)
    assert mo.Event.PAST_LIMIT not in events


def test_a_coast_or_one_stray_reading_past_the_target_is_no_pass() -> None:
    """Rule 5: the few degrees a rotor coasts on past its target (within the margin), or one
    corrupt reading far past it, is no controller heading elsewhere."""
    to_10 = [(10 + 0.5 * i, (330 + 4.0 * i) % 360) for i in range(1, 11)]  # .. 10
    m, events = feed(mo.commanded(ready(az=330), CFG, 10, 10.0), [*to_10, (15.5, 14.0)])
    m, more = feed(m, [(16.0, 17.5), (16.5, 17.5), (17.0, 17.5)])
    assert mo.Event.PASSED not in events + more and m.target_deg == 10
    m, events = feed(mo.commanded(ready(az=330), CFG, 10, 10.0), [*to_10, (15.5, 60.0)])
    m, more = feed(m, [(16.0, 10.5), (16.5, 10.5), (17.0, 10.5)])
    m, last = still(m, 30.0)
    assert mo.Event.PASSED not in events + more + last and mo.Event.ARRIVED in more + last


def test_one_stray_reading_an_overshoot_or_a_reversal_is_no_hand() -> None:
    """Cold review: a single corrupt reading (SPID frames have no checksum), a 1.5 degree
    overshoot with a 1 degree tolerance, the few degrees a rotor coasts on when a new target
    reverses it: each dropped a target the controller was still going to."""
    m, events = feed(spid_moving_to(150), [(10.5, 101), (11, 103), (11.5, 84), (12, 105)], SPID)
    assert events == [] and m.target_deg == 150
    cfg = replace(SPID, tolerance_deg=1)
    m = spid_moving_to(120, tolerance=1)
    m, events = feed(m, [(10.5, 110), (11, 119), (11.5, 121.5), (12, 121), (12.5, 120)], cfg)
    assert mo.Event.TURNED_AWAY not in events
    m = spid_moving_to(150)  # then reversed to 100 while turning up at speed
    m, _ = feed(m, [(10.5, 110), (11, 120)], SPID)
    m = mo.commanded(m, SPID, 100, 11.0)
    m, events = feed(m, [(11.5, 122), (12, 123), (12.5, 118), (13, 110)], SPID)
    assert events == [] and m.target_deg == 100


def test_on_a_wrapping_scale_a_way_that_leads_away_first_is_not_a_hand() -> None:
    """Rule 3: a Rotor-EZ at 170 sent to 190 goes round through north, away from 190 first."""
    m = mo.commanded(ready(az=170), CFG, 190, 10.0)
    readings = [(10 + i * 0.5, 170 - 6.0 * i) for i in range(1, 20)]
    m, events = feed(m, readings)
    assert events == [] and m.target_deg == 190 and m.state is S.MOVING


def test_on_a_wrapping_scale_a_turn_back_on_the_way_is_no_turn_it_was_sent() -> None:
    """Rule 5: a Rotor-EZ on its way from 200 to 300 that turns back at 240 (a poll garbled into
    a jog, a hand at the panel) is heading elsewhere: ``turned back``, some 15 degrees back
    (tolerance, noise and margin beyond the closest it came, twice)."""
    m = mo.commanded(ready(az=200), CFG, 300, 10.0)
    on = [(10 + 0.5 * i, 200 + 3.0 * i) for i in range(1, 14)]  # .. 239
    m, events = feed(m, on)
    assert events == [] and m.target_deg == 300
    back = [(16.5 + 0.5 * i, 239 - 3.0 * i) for i in range(1, 8)]  # 236 .. 218
    m, events = feed(m, back[:3])  # 236, 233, 230: within the margin of the closest, 239
    assert events == [] and m.target_deg == 300
    m, events = feed(m, back[3:5])  # 227 (the first back), 224
    assert events == [mo.Event.TURNED_BACK] and m.target_deg is None and m.state is S.MOVING
    # one stray reading back (within what a reading can have turned), then on its way: no turn
    m = mo.commanded(ready(az=200), CFG, 300, 10.0)
    m, events = feed(m, [*on, (17.0, 226.0), (17.5, 242.0), (18.0, 245.0)])
    assert events == [] and m.target_deg == 300


@pytest.mark.parametrize("ramp", [(2.5, 2.0, 1.5, 1.0), (2.7, 2.4, 2.1, 1.8, 1.5, 1.2)])
def test_a_ramp_down_towards_a_new_target_across_the_stop_is_no_turn_back(
    ramp: tuple[float, ...],
) -> None:
    """A review: a rotor turning up through 270 at 6 degrees a second is sent 20 (its controller
    goes the long way down, its stop at north); it ramps down over 2 or 3 s, closing in on 20
    round the circle, then turns down as asked. The watch of a target sent mid-turn starts
    after twice the settle time."""
    cfg = mo.MotionConfig(REGISTRY["rt21"], tolerance_deg=3, settle_s=1.5, noise_deg=2)
    m = mo.link_up(mo.Motion(), cfg, 0.0)
    m, _ = mo.reading(m, cfg, 240.0, 0.0)
    m, _ = mo.tick(m, cfg, 5.0)
    m = mo.commanded(m, cfg, 300, 10.0)
    m, _ = feed(m, [(10.0 + 0.5 * i, 240 + 3.0 * i) for i in range(1, 11)], cfg)
    m = mo.commanded(m, cfg, 20, 15.0)
    coast, az, t = [], 270.0, 15.0
    for step in ramp:
        t, az = t + 0.5, az + step
        coast.append((t, az))
    way = [(t + 0.5 * i, az - 3.0 * i) for i in range(1, 40)]  # then the long way down
    m, events = feed(m, [*coast, *way], cfg)
    assert mo.Event.TURNED_BACK not in events and m.target_deg == 20


def test_one_reading_ten_degrees_closer_on_the_way_round_is_no_turn_back() -> None:
    """An attack pass: a box that reads tenths (``noise_deg`` 0.1) on its way up the long way
    to 350; one reading 10 degrees low (113.2 read 103.2) closed in once, the true ones after
    it went away: no turn back."""
    cfg = mo.MotionConfig(REGISTRY["easycomm2"], noise_deg=0.1)
    m = mo.link_up(mo.Motion(), cfg, 0.0)
    m, _ = mo.reading(m, cfg, 100.0, 0.0)
    m, _ = mo.tick(m, cfg, 10.0)
    m = mo.commanded(m, cfg, 350.0, 10.0)
    az = [100 + 1.2 * i for i in range(1, 20)]
    az[10] -= 10.0
    m, events = feed(m, [(10.0 + 0.2 * (i + 1), round(a, 1)) for i, a in enumerate(az)], cfg)
    assert events == [] and m.target_deg == 350


def test_a_coast_towards_a_new_target_then_the_long_way_round_is_no_turn_back() -> None:
    """Rule 5: a rotor turning up through 350 is sent 10, and its controller goes round the long
    way (its stop at north): it coasts on 8 degrees towards 10 first, then turns back. A
    target sent mid-turn is watched only after the settle time: the coast is no heading."""
    m = mo.commanded(ready(az=340), CFG, 30, 10.0)
    m, _ = feed(m, [(10.5, 343.0), (11.0, 346.0), (11.5, 349.0)])
    m = mo.commanded(m, CFG, 10, 11.5)
    coast = [(12.0, 353.0), (12.5, 357.0)]
    way = [(12.5 + 0.5 * i, 357 - 3.0 * i) for i in range(1, 116)]  # .. 12 the long way
    m, events = feed(m, [*coast, *way])
    assert mo.Event.TURNED_BACK not in events and mo.Event.PASSED not in events
    assert m.target_deg == 10 and m.position_deg == 12.0


def test_one_corrupt_reading_at_the_target_is_no_arrival_on_the_way_round() -> None:
    """Rule 5: a Rotor-EZ at 170 sent to 190 the way round through north; one corrupt reading
    of 189 (or 200: over 190 from 165) is no pass, and the turn goes on."""
    for stray in (189.0, 200.0):
        m = mo.commanded(ready(az=170), CFG, 190, 10.0)
        readings = [(10 + i * 0.5, 170 - 3.0 * i) for i in range(1, 20)]
        readings[1] = (readings[1][0], stray)
        m, events = feed(m, readings)
        assert events == [] and m.target_deg == 190 and m.state is S.MOVING, stray


def test_a_refusal_drops_the_target_that_has_not_moved_the_rotor() -> None:
    m = mo.commanded(ready(), CFG, 120, 10.0)
    m, events = mo.refused(m, CFG, 10.05)
    assert events == [mo.Event.REFUSED] and m.target_deg is None and m.state is S.BRAKING
    m, _ = mo.tick(m, CFG, 10.05 + CFG.brake_delay_s + mo.BRAKE_GUARD_S)
    assert m.state is S.IDLE and mo.plan_target(m, CFG, m.still_since_t or 0) is mo.Plan.SEND


def test_a_refusal_after_the_rotor_moved_or_at_rest_refers_to_something_else() -> None:
    m = mo.commanded(ready(), CFG, 120, 10.0)
    m, _ = feed(m, [(10.25, 103.0), (10.5, 106.0)])
    turning, events = mo.refused(m, CFG, 10.6)
    assert events == [] and turning == m and turning.target_deg == 120
    idle = ready()
    assert mo.refused(idle, CFG, 20.0) == (idle, [])


def test_a_refusal_of_a_new_bearing_mid_turn_keeps_the_rotor_moving_without_a_target() -> None:
    m = mo.commanded(ready(), CFG, 120, 10.0)
    m, _ = feed(m, [(10.25, 103.0), (10.5, 106.0)])
    m = mo.commanded(m, CFG, 200, 10.6)  # a new bearing while it turns
    m, events = mo.refused(m, CFG, 10.62)
    assert events == [mo.Event.REFUSED] and m.state is S.MOVING and m.target_deg is None


def test_a_status_is_worth_emitting_when_anything_but_the_controllers_clock_changed() -> None:
    """status.py rule 5, the bearing compared first (a turning rotor's every reading)."""
    old = RotatorStatus("r", state=S.MOVING, bearing_deg=100.0, controller_time="12:00:00")
    assert worth_emitting(replace(old, bearing_deg=101.0), old)
    assert worth_emitting(replace(old, bearing_deg=101.0, controller_time="12:00:01"), old)
    assert worth_emitting(replace(old, bearing_deg=None), old)
    assert worth_emitting(replace(old, state=S.BRAKING), old)  # the same bearing, a new state
    assert worth_emitting(replace(old, state=S.BRAKING, controller_time="12:00:01"), old)
    assert not worth_emitting(replace(old), old)
    assert not worth_emitting(replace(old, bearing_deg=float("100")), old)  # equal, not the same
    assert not worth_emitting(replace(old, controller_time="12:00:01"), old)


def test_a_reading_keeps_every_field_it_does_not_change() -> None:
    """A reading makes its new motion without ``replace`` (it runs at every poll): what it
    does not change is kept, field by field, as ``replace`` keeps it."""
    fields = [f for f in mo.Motion.__dataclass_fields__ if f != "state"]
    m = replace(ready(), **{f: 1000.0 + i for i, f in enumerate(fields)})
    m = replace(m, state=S.MOVING, anchor_deg=100.0, position_deg=100.0, target_deg=None)
    moved, _ = mo.reading(m, CFG, 150.0, 2000.0)
    expected = replace(
        m,
        changed_t=2000.0,
        position_deg=150.0,
        el_position_deg=None,
        anchor_deg=150.0,
        el_anchor_deg=None,
        last_move_t=2000.0,
        still_since_t=None,
        lost_turning=False,  # (rule 4: a reading showed it turning)
        az_moved_deg=150.0,  # (rule 2: carried, the azimuth's own movement)
        az_moved_t=2000.0,
        az_crept_deg=0.0,
        az_crept_t=2000.0,  # (rule 2: a creep's speed is measured from here)
    )
    assert moved == mo.tick(expected, CFG, 2000.0)[0]


def _deadline_as_written(m: mo.Motion, cfg: mo.MotionConfig, now: float) -> float | None:
    """next_deadline as its rules say it, every time in a list, the soonest in the future."""
    times: list[float] = []
    if m.state is S.MOVING:  # (arrival and a stop come with a reading: rule 2)
        if m.progress_t is not None and m.target_deg is not None and m.position_deg is not None:
            off = []  # (rule 3: each axis off its target, from its own last movement)
            if mo.angle_error(m.position_deg, m.target_deg, cfg.az_wraps) > cfg.tolerance_deg:
                off.append(m.progress_t if m.az_progress_t is None else m.az_progress_t)
            el, el_target = m.el_position_deg, m.el_target_deg
            if el is not None and el_target is not None and abs(el - el_target) > cfg.tolerance_deg:
                off.append(m.progress_t if m.el_progress_t is None else m.el_progress_t)
            if off:
                times.append(min(off) + cfg.stall_timeout_s)
        ref = max(t for t in (m.last_move_t, m.target_t, m.stop_sent_t, -1e18) if t is not None)
        if m.stop_sent_t is not None:  # (a stop's repeat: from resend, until still)
            times += [m.stop_sent_t + cfg.stop_resend_s, ref + cfg.settle_s]
        elif mo.at_target(m, cfg):  # (plan_target: at its target, no stop once still)
            times.append(ref + cfg.settle_s)
    if m.state in (S.BRAKING, S.STALLED) and m.still_since_t is not None:
        times.append(m.still_since_t + cfg.brake_delay_s)
    if m.idle_not_before_t is not None:
        times.append(m.idle_not_before_t)
    if not cfg.can_report_position:
        if m.busy_until_t is not None:
            times += [m.busy_until_t, m.busy_until_t + cfg.brake_delay_s]
        if m.stop_sent_t is not None:
            times.append(m.stop_sent_t + cfg.brake_delay_s)
            times.append(m.stop_sent_t + cfg.brake_delay_s + mo.BRAKE_GUARD_S)
        if m.kept_end_t is not None:  # (rule 6: the state file's turn kept, over)
            times.append(m.kept_end_t + mo.TURN_KEPT_S)
    future = [t for t in times if t > now]
    return min(future) if future else None


_TIMES = st.one_of(st.none(), st.sampled_from([0.0, 1.0, 2.5, 4.0, 7.0, 9.0, 12.0]))
_CLOCKS = ("last_move_t", "target_t", "stop_sent_t", "stop_read_t", "progress_t", "still_since_t")
_CLOCKS += ("idle_not_before_t", "busy_until_t", "az_progress_t", "el_progress_t", "kept_end_t")


def _motions(states: list[S], **more: st.SearchStrategy[object]) -> st.SearchStrategy[mo.Motion]:
    """Motions in ``states`` with every clock of the machine unset or on a small grid."""
    clocks: dict[str, st.SearchStrategy[object]] = {name: _TIMES for name in _CLOCKS}
    return st.builds(mo.Motion, state=st.sampled_from(states), **clocks, **more)


@settings(max_examples=500)
@given(_motions(list(S)), st.sampled_from([0.0, 3.0, 6.0, 10.0, 20.0]), st.booleans())
def test_the_next_deadline_is_the_soonest_time_ahead_of_every_rule(
    m: mo.Motion, now: float, feedback: bool
) -> None:
    """next_deadline, made without lists (it runs at every step), says what its rules say."""
    cfg = CFG if feedback else DCU
    assert mo.next_deadline(m, cfg, now) == _deadline_as_written(m, cfg, now)


@settings(max_examples=300)
@given(
    _motions(
        [S.MOVING, S.BRAKING, S.IDLE, S.STALLED, S.UNKNOWN],
        position_deg=st.just(100.0),
        anchor_deg=st.just(100.0),
        target_deg=st.sampled_from([None, 95.0, 101.0, 200.0]),
    ),
    st.sampled_from([0.0, 3.0, 6.0, 10.0]),
    st.booleans(),
)
def test_a_motion_tick_left_as_it_was_stays_so_until_its_next_deadline(
    m: mo.Motion, t0: float, feedback: bool
) -> None:
    """motion.py rule 9 (the controller ticks no motion before its next deadline): a motion
    ``tick`` left at ``t0``, or one a stop or a target made from it at ``t0``, is what
    ``tick`` makes of it at any time before ``next_deadline``, and ``plan_target`` says of it
    what it said at ``t0``."""
    cfg = CFG if feedback else DCU
    left, _ = mo.tick(m, cfg, t0)
    for made in (left, mo.stop_sent(left, cfg, t0), mo.commanded(left, cfg, 150.0, t0)):
        assert mo.tick(made, cfg, t0) == (made, [])
        deadline = mo.next_deadline(made, cfg, t0)
        end = t0 + 30.0 if deadline is None else deadline
        plan = mo.plan_target(made, cfg, t0)  # (and what it says of a target: a cold review)
        for t in (t0 + (end - t0) * f for f in (0.25, 0.5, 0.999)):
            assert mo.tick(made, cfg, t) == (made, []), (made, t)
            assert mo.plan_target(made, cfg, t) is plan, (made, t)


AZEL = mo.MotionConfig(
    REGISTRY["gs232b"], tolerance_deg=3, stall_timeout_s=8, brake_delay_s=0, settle_s=1.5,
    noise_deg=2,
)  # fmt: skip
_AZEL_MOTIONS = _motions(
    [S.MOVING, S.IDLE, S.STALLED],
    position_deg=st.sampled_from([100.0, 199.0, 150.0]),
    anchor_deg=st.just(100.0),
    target_deg=st.sampled_from([None, 101.0, 200.0]),
    el_position_deg=st.sampled_from([None, 0.0, 44.0]),
    el_anchor_deg=st.just(0.0),
    el_target_deg=st.sampled_from([None, 45.0]),
)


@settings(max_examples=500)
@given(_AZEL_MOTIONS, st.sampled_from([0.0, 3.0, 6.0, 10.0, 20.0]))
def test_an_az_el_turns_next_deadline_is_the_stall_of_the_axis_judged_first(
    m: mo.Motion, now: float
) -> None:
    """Rule 3 with rule 9: each axis off its target is judged stalled from its own last
    movement (an axis at its target, or one the target leaves out, not at all); the deadline
    is the soonest of them."""
    assert mo.next_deadline(m, AZEL, now) == _deadline_as_written(m, AZEL, now)


@settings(max_examples=300)
@given(_AZEL_MOTIONS, st.sampled_from([0.0, 3.0, 6.0, 10.0]))
def test_an_az_el_motion_left_as_it_was_stays_so_until_its_next_deadline(
    m: mo.Motion, t0: float
) -> None:
    """Rule 9 on an az/el rotor: nothing a per-axis stall (rule 3) makes comes before
    ``next_deadline``."""
    left, _ = mo.tick(m, AZEL, t0)
    for made in (left, mo.commanded(left, AZEL, 150.0, t0, 30.0)):
        assert mo.tick(made, AZEL, t0) == (made, [])
        deadline = mo.next_deadline(made, AZEL, t0)
        end = t0 + 30.0 if deadline is None else deadline
        for t in (t0 + (end - t0) * f for f in (0.25, 0.5, 0.999)):
            assert mo.tick(made, AZEL, t) == (made, []), (made, t)
        if deadline is not None and made.state is S.MOVING and made.target_deg is not None:
            ticked, events = mo.tick(made, AZEL, deadline, asking_since=deadline)
            assert mo.stall_due(made, AZEL, deadline) == (mo.Event.STALLED in events)


@pytest.mark.parametrize(("at", "to"), [(179.0, 181.0), (181.0, 179.0), (180.0, 182.0)])
def test_a_hy_gain_rotor_sent_just_past_its_stop_turns_the_whole_way_round(
    at: float, to: float
) -> None:
    """Rule 5 (``along_travel``): a Rotor-EZ's rotor stops at south, so 179 and 181 are a whole
    turn apart, and a reading of 180 may be at either end: the turn there, away from the target
    on the scale for some 350 degrees, is no pass (an investigation: a sun tracked across south
    was stopped a few degrees into that turn). A GS-232's rotor stops at north: 179 sent 181 is
    there when it goes out, and a turn on away from it is one."""
    way = 1.0 if to < at else -1.0  # (the long way round: away from the target first)
    m = mo.commanded(ready(az=at), CFG, to, 10.0)
    m, events = feed(m, [(10.2 + 0.2 * i, at + way * 1.2 * (i + 1)) for i in range(20)])
    assert mo.Event.PASSED not in events and m.target_deg == to
    gs = mo.MotionConfig(REGISTRY["gs232b"], tolerance_deg=3, settle_s=1.5, noise_deg=2)
    m = mo.link_up(mo.Motion(), gs, 0.0)
    m, _ = mo.reading(m, gs, at, 0.0)
    m, _ = mo.tick(m, gs, 5.0)
    m = mo.commanded(m, gs, to, 10.0)
    m, events = feed(m, [(10.2 + 0.2 * i, at + way * 1.2 * (i + 1)) for i in range(20)], gs)
    assert mo.Event.PASSED in events


def test_a_reading_near_a_hy_gain_rotors_stop_is_where_it_reads() -> None:
    """Rule 5: 181 sent 183 on a Hy-Gain rotor is two degrees along its travel (a reading past
    the stop is not assumed: a review found the blind spot that made), so a turn away from it,
    a garbled target's, is a pass as anywhere else."""
    m = mo.commanded(ready(az=181.0), CFG, 183, 10.0)
    m, events = feed(m, [(10.2 + 0.2 * i, 181 - 1.2 * (i + 1)) for i in range(20)])
    assert mo.Event.PASSED in events


def test_a_dcu1_turn_round_its_stop_is_timed_the_whole_way() -> None:
    """Rule 6: a DCU-1 is timed; 170 to 190 on its Hy-Gain rotor is 340 degrees round its stop
    at south, not 20 (a review: taken as over in 7 s, the next target went into the turn); the
    other way across north, 350 to 10, is timed the longer way too (the stop is only assumed to
    be at south: a stop first, never a target into a turn)."""
    m = mo.link_up(mo.Motion(), DCU, 0.0)
    m = mo.commanded(m, DCU, 170, 0.0)
    m, _ = mo.tick(m, DCU, 200.0)
    m = mo.commanded(m, DCU, 190, 200.0)
    assert m.busy_until_t is not None and m.busy_until_t - 200.0 >= 340 / 6.0
    m, _ = mo.tick(m, DCU, 400.0)
    m = mo.commanded(mo.commanded(m, DCU, 350, 400.0), DCU, 10, 400.0)
    assert m.busy_until_t is not None and m.busy_until_t - 400.0 >= 340 / 6.0
