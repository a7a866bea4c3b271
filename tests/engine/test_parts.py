"""The session's parts on their own, as pure objects: each gets a read-only view and the time
and returns what it proposes (docs/architecture.md, "parts decide and return"). The scenarios
in virtual time (test_session_*.py) prove them wired into the session."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import pytest

from bridge.app import worker_config
from bridge.core.model import ErrorKind, MotionState, Source, Stop, Target
from bridge.session import motion as mo
from bridge.session import slew as slewing
from bridge.session.autopark import AutoPark
from bridge.session.config import WorkerConfig
from bridge.session.link import Link
from bridge.session.mailbox import Batch
from bridge.session.options import OPTIONS_REFRESH_S, Options
from bridge.session.parts import NOTHING, Scene, Speeds, Unjudged
from bridge.session.slew import Slew
from bridge.session.stops import STOP_REPEAT_GAP_S, STOP_TRIES_BEFORE_ERROR, Fence, Stops
from bridge.session.targets import Go, Targets, decide
from bridge.session.tracking import Tracker
from bridge.settings import RotatorSettings
from bridge.sky import Body, Sky
from bridge.sky.worker import PassQuestion
from tests.engine.virtual import VirtualRotator

IDLE_AT_90 = mo.Motion(state=MotionState.IDLE, position_deg=90.0, anchor_deg=90.0)


def rig(model: str = "rotorez", sky: Sky | None = None, **settings: Any) -> WorkerConfig:
    rotator = RotatorSettings.model_validate(
        {"id": "p", "model": model, "port": "/dev/null", **settings}
    )
    return worker_config(rotator, sky)


def scene(now: float, motion: mo.Motion = IDLE_AT_90, **kw: Any) -> Scene:
    seen: dict[str, Any] = dict(
        pending=None, locked=False, parked=False, slewing=False, speeds=Speeds(6.0, 3.0)
    )
    return Scene(now=now, motion=motion, wall_offset_s=1_750_000_000.0, **{**seen, **kw})


# -- auto-park -------------------------------------------------------------------------------
def test_auto_park_proposes_the_park_after_a_quiet_spell_and_only_when_free() -> None:
    park = AutoPark(rig(park_az_deg=0, park_after_idle_s=60))
    park.activity(0.0)
    assert park.step(scene(59.0)) is NOTHING
    assert park.wakeup(59.0) == 60.0
    for busy in (
        {"locked": True},
        {"parked": True},
        {"motion": replace(IDLE_AT_90, state=MotionState.BRAKING)},
        {"motion": replace(IDLE_AT_90, idle_not_before_t=61.5)},  # no brake, settling
    ):
        assert park.step(scene(61.0, **busy)) is NOTHING, busy
    proposal = park.step(scene(61.0))
    assert proposal.target is not None and proposal.target.park
    assert proposal.target.source is Source.AUTO_PARK and proposal.error is None
    assert park.step(scene(62.0)) is NOTHING  # rule 3: the park itself is activity


def test_auto_park_judged_unjudged_is_judged_again_at_the_next_step() -> None:
    """autopark.py rule 5: a whole park that cannot be judged yet (a rotator of two boxes'
    azimuth box back, its first reading not taken) is no park tried: the next step parks, not
    the next quiet spell (review 63)."""
    park = AutoPark(rig(park_az_deg=0, park_after_idle_s=60))
    park.activity(0.0)
    fresh = [False]

    def whole(target: Target) -> None:
        if not fresh[0]:
            raise Unjudged(target)

    assert park.step(scene(61.0, whole=whole)) is NOTHING  # the azimuth box not read yet
    fresh[0] = True  # its first reading, a poll later
    proposal = park.step(scene(62.0, whole=whole))
    assert proposal.target is not None and proposal.target.source is Source.AUTO_PARK


def test_a_rotor_seen_turning_starts_the_quiet_spell_again() -> None:
    park = AutoPark(rig(park_az_deg=0, park_after_idle_s=60))
    park.activity(0.0)
    turning = replace(IDLE_AT_90, state=MotionState.MOVING)
    assert park.step(scene(50.0, motion=turning)) is NOTHING
    assert park.step(scene(61.0)) is NOTHING
    assert park.step(scene(110.0)).target is not None


def test_without_a_quiet_spell_set_auto_park_never_proposes() -> None:
    park = AutoPark(rig(park_az_deg=0))
    park.activity(0.0)
    assert park.step(scene(1e6)) is NOTHING and park.wakeup(0.0) is None


# -- tracking ----------------------------------------------------------------------------------
def test_tracking_asks_the_sky_and_proposes_nothing_until_the_answer() -> None:
    tracker = Tracker(rig("md01", sky=Sky(52.52, 13.29)))
    assert tracker.step(scene(0.0)) is NOTHING  # nothing tracked
    tracker.start(Body.sun())
    proposal = tracker.step(scene(0.0))
    assert proposal.target is None and proposal.busy  # tracking.py rules 7 and 8
    asks = tracker.take_asks()
    assert [type(q) for q in asks] == [PassQuestion] and tracker.take_asks() == []
    assert tracker.step(scene(1.0)).target is None and tracker.take_asks() == []  # asked once
    generation = tracker.generation
    assert tracker.end("stop") and tracker.ended == "stop"
    assert tracker.generation > generation  # the answer to come is stale


def test_tracking_under_the_lock_is_activity_and_nothing_else() -> None:
    tracker = Tracker(rig("md01", sky=Sky(52.52, 13.29)))
    tracker.start(Body.sun())
    proposal = tracker.step(scene(0.0, locked=True))
    assert proposal.busy and proposal.target is None and tracker.take_asks() == []


# -- slew recovery -----------------------------------------------------------------------------
def slew(stops: int = 0, attempt: int = 1) -> Slew:
    return Slew(0.0, 10.0, 0.0, 200.0, 30.0, Source.MQTT, stops, attempt)


def test_a_lost_slew_report_is_stopped_and_its_target_tried_once_more() -> None:
    cfg = rig("satel")
    first = slewing.overdue(cfg, slew(), 1.0, 120.0)
    assert first.stop and first.retry is not None and first.attempt == 2
    assert first.error is not None and first.error.kind is ErrorKind.SERIAL
    second = slewing.overdue(cfg, slew(attempt=2), 1.0, 120.0)
    assert second.stop and second.retry is None and second.error is not None  # given up


def test_a_stop_during_a_slew_is_repeated_then_the_controller_is_asked() -> None:
    cfg = rig("satel")
    assert slewing.overdue(cfg, slew(stops=1), 1.0, 5.0) == slewing.Overdue(stop=True)
    last = slewing.overdue(cfg, slew(stops=slewing.SLEW_STOP_TRIES), 1.0, 5.0)
    assert not last.stop and last.track_lost and last.error is not None
    assert slewing.overdue(cfg, None, 1.0, 5.0) == slewing.Overdue(stop=False)


# -- stops -------------------------------------------------------------------------------------
def test_a_second_stop_in_the_brake_window_adds_nothing_unless_a_target_went_out() -> None:
    cfg, stops = rig().motion, Stops()
    stopped = replace(IDLE_AT_90, state=MotionState.BRAKING, stop_sent_t=10.0)
    assert stops.merges(stopped, cfg, 11.0)
    assert not stops.merges(stopped, cfg, 10.0 + max(cfg.brake_delay_s, 1.0))
    assert not stops.merges(replace(stopped, target_deg=200.0), cfg, 11.0)
    # a stop of a rotor that may still turn (its last stop's frame may have been lost):
    # merged only within STOP_REPEAT_GAP_S of that stop, and then owed at the gap's end
    # (stops.py rule 1); never once a reading showed it turning since, never on a controller
    # silent while it turns
    turning = replace(stopped, state=MotionState.MOVING, last_move_t=9.9)
    assert not stops.merges(turning, cfg, 10.001 + STOP_REPEAT_GAP_S)
    assert stops.repeat_at(turning) is None
    assert stops.merges(turning, cfg, 10.05)
    assert stops.repeat_at(turning) == pytest.approx(10.0 + STOP_REPEAT_GAP_S)
    assert not stops.merges(replace(turning, last_move_t=10.02), cfg, 10.05)
    assert not stops.merges(turning, rig("satel").motion, 10.05)


def test_a_repeat_merged_into_a_stop_goes_out_when_its_gap_ends_unless_the_rotor_stopped() -> None:
    """A lost stop frame, then the operator's second STOP 50 ms later: merged, and sent at
    the gap's end (no try counted), not stop_resend_s later; a reading that showed the rotor
    still in between, or a newer stop sent meanwhile, leaves nothing owed."""
    cfg = rig().motion
    turning = replace(IDLE_AT_90, state=MotionState.MOVING, stop_sent_t=10.0, last_move_t=9.9)
    stops = Stops()
    assert stops.merges(turning, cfg, 10.05)
    assert not stops.repeat_due(turning, 10.09)  # not yet: the gap
    assert stops.repeat_due(turning, 10.001 + STOP_REPEAT_GAP_S)
    assert not stops.repeat_due(turning, 10.2)  # once
    assert stops.check(turning, cfg, 10.2, False) == (False, None)  # and no try counted
    stops = Stops()
    assert stops.merges(turning, cfg, 10.05)
    still = replace(turning, state=MotionState.BRAKING)  # a reading: it took
    assert stops.repeat_at(still) is None and not stops.repeat_due(still, 10.2)
    assert stops.repeat_at(replace(turning, stop_sent_t=10.08)) is None  # a newer stop went
    assert stops.repeat_at(replace(turning, target_deg=200.0)) is None  # a target went
    # one repeat a stop: once it went, later stops merge until a reading shows the rotor turn
    stops = Stops()
    assert stops.merges(turning, cfg, 10.05) and stops.repeat_due(turning, 10.1)
    stops.sent(10.1)
    repeated = replace(turning, stop_sent_t=10.1)
    assert stops.merges(repeated, cfg, 10.5) and stops.merges(repeated, cfg, 11.5)
    assert stops.repeat_at(repeated) is None  # nothing owed for those
    assert not stops.merges(replace(repeated, last_move_t=10.4), cfg, 10.5)  # it turns: sent
    stops.sent(10.5)  # a stop anew (not the repeat): one repeat may follow it again
    anew = replace(turning, stop_sent_t=10.5)
    assert not stops.merges(anew, cfg, 10.7)


def test_a_stop_that_did_not_take_is_sent_again_and_the_last_try_says_so() -> None:
    cfg, stops = rig().motion, Stops()
    moved_t = 20.0 - cfg.settle_s / 2  # a movement seen since the stop, settle_s not over
    turning = replace(
        IDLE_AT_90,
        state=MotionState.MOVING,
        stop_sent_t=10.0,
        stop_read_t=10.2,
        last_move_t=moved_t,
    )
    first = replace(turning, stop_read_t=moved_t)  # its only movement: where the stop found it
    assert stops.check(first, cfg, 20.0, False) == (False, None)
    assert stops.check(turning, cfg, 10.5, False) == (False, None)  # not late yet
    assert stops.check(turning, cfg, 20.0, True) == (False, None)  # a target stops it anyway
    # one settle_s after its last movement, the next reading may find it still (motion rule 2)
    assert stops.check(turning, cfg, moved_t + cfg.settle_s, False) == (False, None)
    tries = [stops.check(turning, cfg, 20.0, False) for _ in range(STOP_TRIES_BEFORE_ERROR)]
    assert all(again for again, _ in tries)
    assert [e is None for _, e in tries] == [True] * (STOP_TRIES_BEFORE_ERROR - 1) + [False]


def test_a_rotor_turned_away_is_stopped_once_at_rest() -> None:
    cfg, stops = rig().motion, Stops()
    away = stops.verdict(mo.Event.TURNED_AWAY, IDLE_AT_90, cfg)
    assert not away.stop and away.ends_tracking and away.error is not None
    assert stops.verdict(mo.Event.STOPPED, IDLE_AT_90, cfg).stop
    assert not stops.verdict(mo.Event.STOPPED, IDLE_AT_90, cfg).stop  # once
    stalled = stops.verdict(mo.Event.STALLED, IDLE_AT_90, cfg)
    assert stalled.stop and stalled.error is not None and stalled.error.kind is ErrorKind.STALLED


def test_the_fence_holds_until_its_marker_and_a_clearing_release_says_so() -> None:
    fence = Fence()
    assert not fence.apply(Batch(stop=Stop(), hold=3)) and fence.held
    assert not fence.apply(Batch(release=2)) and fence.held
    assert not fence.apply(Batch(release=3)) and not fence.held
    fence.apply(Batch(hold=4))
    assert fence.apply(Batch(release_clear=True)) and not fence.held
    assert not fence.apply(Batch(release_clear=True))  # nothing was held


def test_the_stop_expresss_hold_has_numbers_of_its_own_and_only_its_answer_ends_it() -> None:
    """stops.py rule 5: a lane marker or a clearing release (the main connection's) says
    nothing of the stop express's frame; only its answer does."""
    fence = Fence()
    fence.apply(Batch(express_hold=2))
    fence.apply(Batch(stop=Stop(), hold=1))
    fence.apply(Batch(release=5))  # the lane's marker, numbered above the express's word
    assert fence.held
    fence.apply(Batch(release_clear=True))
    assert fence.held
    fence.apply(Batch(express_release=1))
    assert fence.held
    fence.apply(Batch(express_release=2))
    assert not fence.held


# -- options -----------------------------------------------------------------------------------
def test_options_go_out_when_idle_and_free_and_again_after_the_refresh() -> None:
    options = Options({"b": True, "a": False})
    options.connected(answering=True)
    assert options.take(idle=False, free=True, now=0.0) == []
    assert options.take(idle=True, free=False, now=0.0) == []
    assert options.take(idle=True, free=True, now=1.0) == [("a", False), ("b", True)]
    assert options.take(idle=True, free=True, now=2.0) == []
    options.set("a", True, connected=True)
    assert options.take(idle=True, free=True, now=3.0) == [("a", True)]
    assert options.take(idle=True, free=True, now=3.0 + OPTIONS_REFRESH_S) == [
        ("a", True),
        ("b", True),
    ]


# -- the pending target's way to the wire --------------------------------------------------------
def line(cfg: WorkerConfig, reading_t: float | None = None) -> Link:
    link = Link(cfg.spec.codec_factory(), cfg.spec, 0.0, cfg.baud)
    if reading_t is not None:
        link.got_reading(reading_t)
    return link


def pending(cfg: WorkerConfig, az_deg: float, now: float = 10.0) -> Targets:
    targets = Targets(cfg)
    targets.put(Target(az_deg), now)
    return targets


def test_a_target_goes_out_only_when_nothing_comes_first() -> None:
    cfg = rig()  # Rotor-EZ: stops to re-target, so it asks for a fresh reading first
    idle = replace(IDLE_AT_90, still_since_t=0.0)
    assert decide(cfg, line(cfg, 9.9), idle, pending(cfg, 200), False, 10.0).go is Go.SEND
    assert decide(cfg, line(cfg, 9.9), idle, pending(cfg, 200), True, 10.0).go is Go.WAIT  # held
    assert decide(cfg, line(cfg, 1.0), idle, pending(cfg, 200), False, 10.0).go is Go.ASK_FIRST
    turning = replace(idle, state=MotionState.MOVING)
    assert decide(cfg, line(cfg, 9.9), turning, pending(cfg, 200), False, 10.0).go is Go.STOP_FIRST
    braking = replace(idle, state=MotionState.BRAKING)
    assert decide(cfg, line(cfg, 9.9), braking, pending(cfg, 200), False, 10.0).go is Go.WAIT


def test_a_target_the_rotor_is_already_at_is_done_without_a_frame() -> None:
    cfg = rig()
    done = decide(cfg, line(cfg, 9.9), IDLE_AT_90, pending(cfg, 91), False, 10.0)
    assert done.go is Go.DONE and done.wire == (91.0, None)


def test_a_part_that_is_off_is_never_run_and_one_that_is_on_runs_while_the_rotor_turns(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """session.py rule 17: auto-park without a park time is never called (a step with nothing
    for it costs nothing); with one, it sees the turn (its quiet spell starts again)."""
    calls: list[float] = []
    step = AutoPark.step

    def counted(part: AutoPark, seen: Scene) -> Any:
        calls.append(seen.now)
        return step(part, seen)

    monkeypatch.setattr(AutoPark, "step", counted)
    for park in ({}, {"park_az_deg": 0, "park_after_idle_s": 600}):
        calls.clear()
        with VirtualRotator("rotorez", settings=park) as v:
            v.run_until_state(MotionState.IDLE, 30)
            v.target(120)
            v.run_until(lambda h: h.state is MotionState.IDLE and h.truth().az_deg > 110, 120)
        assert (len(calls) > 0) == bool(park), park
