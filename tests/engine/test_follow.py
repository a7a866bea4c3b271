"""Following the QSO partner (session/follow.py): the part on its own, on read-only scenes and
a fake time; then wired into the session in virtual time against an emulated controller
(tests/engine/virtual.py). Bearings are checked against the vector great circle of
tests/integration/test_pointing_bridge.py, not the bridge's core/geo.py."""

from __future__ import annotations

import logging
from dataclasses import replace
from typing import Any

import pytest

from bridge.app import worker_config
from bridge.core.model import ErrorKind, MotionState, Source
from bridge.features.follow import follow_state
from bridge.session import follow as fo
from bridge.session import session as fs
from bridge.session.config import FollowConfig, WorkerConfig
from bridge.session.follow import Follow, Follower, Heard
from bridge.session.parts import NOTHING, Scene
from bridge.settings import RotatorSettings
from bridge.sky import Body, Sky
from tests.engine.test_parts import IDLE_AT_90, scene
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between, locator_centre, reference_path

BERLIN = locator_centre("JO62QM")
STATION = FollowConfig(BERLIN, wsjtx=True)


def centre(grid: str) -> tuple[float, float]:
    """The centre of a 4- or 6-character locator (a 4-character square is 2 x 1 degrees)."""
    if len(grid) == 6:
        return locator_centre(grid)
    up = grid.upper()
    lon = -180 + (ord(up[0]) - ord("A")) * 20 + int(up[2]) * 2 + 1.0
    lat = -90 + (ord(up[1]) - ord("A")) * 10 + int(up[3]) + 0.5
    return lat, lon


def bearing(grid: str, long_path: bool = False) -> float:
    b = reference_path(BERLIN, centre(grid))[0]
    return (b + 180.0) % 360.0 if long_path else b


def rig(follow: FollowConfig = STATION, **settings: Any) -> WorkerConfig:
    rotator = RotatorSettings.model_validate(
        {"id": "p", "model": "md01", "port": "/dev/null", **settings}
    )
    return worker_config(rotator, None, follow)


def following(cfg: WorkerConfig, long_path: bool = False, now: float = 0.0) -> Follower:
    part = Follower(cfg)
    part.start(Follow(True, long_path), now)
    return part


def at(now: float) -> Scene:
    return scene(now)


# -- the part ---------------------------------------------------------------------------------
def test_off_it_proposes_nothing_whatever_it_hears() -> None:
    part = Follower(rig())
    part.heard(Heard("JA1ABC", "PM95", False), 0.0)
    assert part.step(at(0.0)) is NOTHING and not part.on


def test_a_new_grid_is_turned_to_and_the_same_grid_never_again() -> None:
    part = following(rig())
    part.heard(Heard("JA1ABC", "PM95", False), 1.0)
    first = part.step(at(1.0))
    assert first.target is not None and first.target.source is Source.WSJTX and first.busy
    assert first.target.az_deg is not None
    assert angle_between(first.target.az_deg, bearing("PM95")) < 0.1
    info = part.info
    assert info is not None and (info.call, info.grid, info.path) == ("JA1ABC", "PM95", "short")
    assert info.bearing_deg is not None and angle_between(info.bearing_deg, bearing("PM95")) < 0.1
    assert info.distance_km == pytest.approx(reference_path(BERLIN, centre("PM95"))[1], rel=0.01)
    for later, heard in enumerate(
        [
            Heard("JA1ABC", "PM95", False),
            Heard("JA1ABC", " pm95 ", False),  # the same square, however written
            Heard("JA1XYZ", "PM95", False),  # another call in the same square: no new bearing
            Heard("JA1ABC", "", False),  # no grid
            Heard("JA1ABC", "XX99", False),  # no locator
        ]
    ):
        part.heard(heard, 2.0 + later)
        proposal = part.step(at(2.0 + later))
        assert proposal.target is None and proposal.error is None, heard
    part.heard(Heard("JA1ABC", "PM95vq", False), 9.0)  # a finer square is a new grid
    finer = part.step(at(9.0))
    assert finer.target is not None and finer.target.az_deg is not None
    assert angle_between(finer.target.az_deg, bearing("PM95VQ")) < 0.1


def test_a_new_grid_while_transmitting_waits_for_the_transmission_to_end() -> None:
    part = following(rig())
    part.heard(Heard("VK2XYZ", "QF56", True), 1.0)
    for now in (1.0, 5.0, 14.0):
        assert part.step(at(now)).target is None
    assert part.info is not None and part.info.held
    part.heard(Heard("VK2XYZ", "QF56", False), 15.0)
    proposal = part.step(at(15.0))
    assert proposal.target is not None and part.info is not None and not part.info.held


def test_a_held_grid_that_goes_away_holds_nothing_any_more() -> None:
    part = following(rig())
    part.heard(Heard("JA1ABC", "PM95", False), 1.0)
    assert part.step(at(1.0)).target is not None
    part.heard(Heard("VK2XYZ", "QF56", True), 2.0)
    part.step(at(2.0))
    assert part.info is not None and part.info.held
    part.heard(Heard("JA1ABC", "PM95", True), 3.0)  # back to the partner turned to
    assert part.step(at(3.0)).target is None
    assert part.info is not None and not part.info.held


def test_a_turn_by_no_target_of_its_own_away_from_its_bearing_ends_it_its_own_is_held() -> None:
    """Rule 1: a hand at the front panel (turning, no target and no stop of the bridge's out,
    further than the tolerance from the bearing last turned to) ends following, transmitting or
    not; rule 3: its own turn (a target out, still turning) is held while it transmits."""
    part = following(rig())
    part.heard(Heard("JA1ABC", "PM95", False), 1.0)
    target = part.step(at(1.0)).target
    assert target is not None and target.az_deg is not None
    pm95 = bearing("PM95")
    turning = replace(IDLE_AT_90, state=MotionState.MOVING, target_deg=None)
    by_hand = replace(turning, position_deg=(pm95 + 40.0) % 360.0)
    own = replace(by_hand, target_deg=target.az_deg)
    stopped = replace(by_hand, stop_sent_t=1.5)  # the rotor coasting after a stop of ours
    jitter = replace(turning, position_deg=(pm95 + 2.0) % 360.0)  # within the tolerance (3)
    for transmitting in (False, True):
        part.heard(Heard("JA1ABC", "PM95", transmitting), 2.0)
        for motion in (stopped, jitter):
            quiet = part.step(scene(2.0, motion))
            assert quiet.ended is None and not quiet.halt and quiet.target is None
        ended = part.step(scene(2.0, by_hand))
        assert ended.ended == "turned by hand"
        assert ended.target is None and not ended.halt
    held = part.step(scene(2.0, own))  # transmitting: its own turn stops
    assert held.halt and held.ended is None and part.info is not None and part.info.held
    part.heard(Heard("JA1ABC", "PM95", False), 15.0)
    again = part.step(scene(15.0, replace(IDLE_AT_90, position_deg=(pm95 + 20.0) % 360.0)))
    assert again.target is not None and again.ended is None  # and goes on after it


def test_without_hold_while_tx_a_transmitting_status_turns_it_at_once() -> None:
    part = following(rig(follow_hold_while_tx=False))  # the rotator's key
    part.heard(Heard("VK2XYZ", "QF56", True), 1.0)
    assert part.step(at(1.0)).target is not None


def test_the_long_path_is_the_other_way() -> None:
    part = following(rig(), long_path=True)
    part.heard(Heard("W1AW", "FN31", False), 1.0)
    proposal = part.step(at(1.0))
    assert proposal.target is not None and proposal.target.az_deg is not None
    assert angle_between(proposal.target.az_deg, bearing("FN31", long_path=True)) < 0.1
    assert part.info is not None and part.info.path == "long"


def test_switching_on_takes_a_fresh_status_and_never_a_stale_one() -> None:
    fresh = Follower(rig())
    fresh.heard(Heard("JA1ABC", "PM95", False), 0.0)
    fresh.start(Follow(True), fo.FRESH_S - 1.0)
    assert fresh.step(at(fo.FRESH_S - 1.0)).target is not None
    stale = Follower(rig())
    stale.heard(Heard("JA1ABC", "PM95", False), 0.0)
    stale.start(Follow(True), fo.FRESH_S + 1.0)
    assert stale.step(at(fo.FRESH_S + 1.0)).target is None


def test_a_grid_the_judge_refuses_is_reported_once_and_not_tried_again() -> None:
    east = bearing("PM95")
    part = following(rig(keep_out=[[east - 10.0, east + 10.0]]))
    part.heard(Heard("JA1ABC", "PM95", False), 1.0)
    refused = part.step(at(1.0))
    assert refused.target is None and refused.error is not None
    assert refused.error.kind is ErrorKind.REFUSED and "keep-out" in refused.error.message
    assert refused.error.command == "follow JA1ABC PM95"
    part.heard(Heard("JA1ABC", "PM95", False), 2.0)
    assert part.step(at(2.0)).error is None
    part.heard(Heard("W1AW", "FN31", False), 3.0)
    assert part.step(at(3.0)).target is not None


def test_a_second_program_on_the_port_never_swings_the_rotor_between_two_partners() -> None:
    """Two WSJT-X instances (two bands, --rig-name) or a second station's WSJT-X in the same
    multicast group each send their status at every decoding period: following takes the
    instance it heard first and ignores the other, or the rotor would turn between the two
    partners twice a minute."""
    part = following(rig())
    part.heard(Heard("JA1ABC", "PM95", False, "WSJT-X - 20m"), 1.0)
    assert part.step(at(1.0)).target is not None
    for now in (2.0, 4.0, 6.0):  # the other instance's QSO, then the first one's again
        part.heard(Heard("W1AW", "FN31", False, "WSJT-X - 6m"), now)
        assert part.step(at(now)).target is None
        part.heard(Heard("JA1ABC", "PM95", False, "WSJT-X - 20m"), now + 1.0)
        assert part.step(at(now + 1.0)).target is None
    assert part.info is not None and part.info.grid == "PM95"
    part.heard(Heard("VK2XYZ", "QF56", False, "WSJT-X - 20m"), 8.0)  # its next partner
    assert part.step(at(8.0)).target is not None
    part.end("off")  # switched on again, it takes whichever it hears first then
    part.heard(Heard("W1AW", "FN31", False, "WSJT-X - 6m"), 9.0)
    part.start(Follow(True), 9.5)
    assert part.step(at(9.5)).target is not None
    part.heard(Heard("JA1ABC", "PM95", False, "WSJT-X - 20m"), 10.0)
    assert part.step(at(10.0)).target is None


def test_a_flood_of_new_grids_is_logged_a_line_every_few_seconds_not_one_a_turn(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """An attack pass: a program on WSJT-X's port sent a status with a new grid every few
    milliseconds (within its budget, 200 a second); each turn was an INFO line, some 100 log
    lines a second. Every turn is still proposed; its INFO line comes at most once per
    TURN_LOG_S, saying how many turns came since the last one."""
    part = following(rig())
    grids = ["PM95", "FN31", "QF56", "JJ00"]
    with caplog.at_level(logging.INFO, logger=fo.log.name):
        for i in range(400):  # two seconds of a flood
            now = 1.0 + i * 0.005
            part.heard(Heard("JA1ABC", grids[i % len(grids)], False), now)
            assert part.step(at(now)).target is not None
        said = [r for r in caplog.records if r.levelno >= logging.INFO]
        assert len(said) == 1 and "following JA1ABC in PM95" in said[0].getMessage()
        part.heard(Heard("JA1ABC", "FN31", False), 1.0 + fo.TURN_LOG_S)
        assert part.step(at(1.0 + fo.TURN_LOG_S)).target is not None
    said = [r.getMessage() for r in caplog.records if r.levelno >= logging.INFO]
    assert len(said) == 2 and "following JA1ABC in FN31" in said[1], said
    assert "399 more turn(s) since the last such line" in said[1], said


def test_a_flood_of_refused_grids_is_on_r_error_each_and_in_the_log_a_line_every_few_seconds(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """An attack pass: a status every 5 ms, each with a new grid in a keep-out sector (the
    whole compass but 359..360 here): each refusal was a warning line of the session's, some
    190 a second in the bridge. Each refusal is still published (R/error's own limit thins
    it there); the log says one every PART_ERROR_LOG_S with the count since (session.py rule
    22), and the rotor never turns."""
    grids = [f"{a}{b}{n}{m}" for a in "AJR" for b in "ACEGIKMOQ" for n in "0369" for m in "0369"]
    with spid(keep_out=[[0.0, 359.0]]) as v:
        v.follow(True)
        with caplog.at_level(logging.DEBUG, "bridge.session.session"):
            for grid in grids[:400]:  # two seconds of a flood
                v.heard("JA1ABC", grid)
                v.run_for(0.005)
            v.run_for(fs.PART_ERROR_LOG_S)
            v.heard("JA1ABC", grids[400])
            v.run_for(0.1)
        refused = [e for e in v.errors("refused") if e.message.startswith("following: ")]
        assert len(refused) == 401
        said = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
        assert len(said) == 2 and "keep-out sector" in said[0], said
        assert said[1].endswith("(399 more such error(s) since the last such line)"), said
        assert sets(v) == 0


def test_the_stations_own_grid_and_its_antipode_have_no_bearing_and_are_reported_once() -> None:
    """JO62QM is the station's own subsquare (distance 0); AD67QL is its antipode's (every
    bearing a great circle to it): neither turns the rotor nor breaks following."""
    part = following(rig())
    for now, grid in ((1.0, "JO62QM"), (2.0, "AD67QL")):
        part.heard(Heard("XX1XX", grid, False), now)
        proposal = part.step(at(now))
        assert proposal.target is None and proposal.error is not None, grid
        assert proposal.error.kind is ErrorKind.REFUSED and "bearing" in proposal.error.message
        part.heard(Heard("XX1XX", grid, False), now + 0.5)
        assert part.step(at(now + 0.5)).error is None  # once
    assert part.on
    part.heard(Heard("JA1ABC", "PM95", False), 3.0)
    assert part.step(at(3.0)).target is not None


def test_ending_says_why_and_whether_it_was_on() -> None:
    part = following(rig())
    assert part.end("stop") and part.ended == "stop" and part.info is None
    assert not part.end("stop again")
    part.start(Follow(True), 10.0)
    assert part.ended is None and part.on


# -- in the session, in virtual time ------------------------------------------------------------
def spid(**settings: Any) -> VirtualRotator:
    v = VirtualRotator(
        "md01",
        settings={"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0, **settings},
        emulator={"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0},
        follow=STATION,
    )
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    return v


def sets(v: VirtualRotator) -> int:
    return len(v.frames("set"))


def test_the_session_turns_the_rotor_to_the_partner_and_a_stop_ends_it() -> None:
    with spid() as v:
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_until(lambda h: h.state is MotionState.IDLE and h.truth().az_deg > 1, 60, "there")
        assert angle_between(v.truth().az_deg, bearing("PM95")) <= 0.5
        assert v.status.last_command_source == "wsjtx"
        assert v.status.following is not None and v.status.following.grid == "PM95"
        n = sets(v)
        v.heard("JA1ABC", "PM95")
        v.run_for(30.0)
        assert sets(v) == n  # the same grid moves nothing
        v.stop()
        assert v.status.following is None and v.status.following_ended == "stop"
        v.heard("W1AW", "FN31")
        v.run_for(30.0)
        assert sets(v) == n and not v.truth().is_moving


ENDED = {  # what the status says ended following
    "target": "mqtt target",
    "lock": "lock",
    "track": "tracking sun",
    "off": "off",
    "link": "serial link down",
}


@pytest.mark.parametrize("how", list(ENDED))
def test_anything_else_ends_following_and_the_rotor_never_turns_by_itself_after(how: str) -> None:
    with VirtualRotator(
        "md01",
        settings={"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0},
        emulator={"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0},
        follow=STATION,
        sky=Sky(*BERLIN),
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_until(lambda h: h.state is MotionState.IDLE and h.truth().az_deg > 1, 60, "there")
        if how == "target":
            v.target(200.0)
        elif how == "lock":
            v.lock(True)
        elif how == "track":
            v.track(Body.sun())
        elif how == "off":
            v.follow(False)
        else:
            v.link_down()
            v.run_for(5.0)
            v.link_up()
        v.run_for(2.0)
        assert v.status.following is None
        assert v.status.following_ended == ENDED[how]
        if how == "track":
            v.track(None)
        v.run_until(lambda h: not h.truth().is_moving, 60, "still")
        n = sets(v)
        v.heard("W1AW", "FN31")
        v.run_for(60.0)
        assert sets(v) == n


def test_a_transmission_beginning_during_the_turn_holds_the_rotor_until_it_ends() -> None:
    """The usual FT8 case: a double-click on a CQ near the end of a receive period names the
    grid (not yet transmitting), and the transmission starts a second later, long before the
    turn is over. With follow_hold_while_tx the beam does not turn while it transmits: the turn
    stops, and goes on to the same grid once the transmission has ended."""
    with spid() as v:
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(1.5)
        v.heard("JA1ABC", "PM95", True)  # the transmission starts
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "the turn stopped")
        where = v.truth().az_deg
        assert angle_between(where, bearing("PM95")) > 5  # stopped on the way
        assert v.status.following is not None and v.status.following.held
        v.run_for(11.0)  # the rest of the 12.6 s transmission
        assert abs(v.truth().az_deg - where) <= 0.5  # still while it transmits
        v.heard("JA1ABC", "PM95", False)  # it has ended
        v.run_until(lambda h: h.state is MotionState.IDLE and h.truth().az_deg > where + 1, 60, "")
        assert angle_between(v.truth().az_deg, bearing("PM95")) <= 0.5
        assert v.status.following is not None and not v.status.following.held


def _turned_by_hand_while_following(v: VirtualRotator, transmission: bool) -> float:
    """Following, the rotor at the partner's bearing: the operator turns the beam by hand at
    the controller's panel toward 300, and WSJT-X's next status (the same partner) comes while
    the rotor turns, transmitting or not, and the transmission ends. Run until a minute after
    the rotor is at rest; when the hand came."""
    v.follow(True)
    v.heard("JA1ABC", "PM95")
    v.run_until(lambda h: h.state is MotionState.IDLE and h.truth().az_deg > 1, 60, "there")
    assert angle_between(v.truth().az_deg, bearing("PM95")) <= 0.5
    v.run_for(5.0)
    hand = v.now
    v.manual_rotate(300.0)  # a hand at the panel
    v.run_until(lambda h: h.truth().is_moving and h.state is MotionState.MOVING, 10, "turning")
    v.run_for(4.0)  # some 40 degrees of it
    v.heard("JA1ABC", "PM95", transmission)  # WSJT-X's next status
    v.run_for(3.0)
    v.heard("JA1ABC", "PM95", False)  # (the transmission, if any, has ended)
    v.run_until(lambda h: not h.truth().is_moving, 60, "the hand's turn over")
    v.run_for(60.0)
    return hand


@pytest.mark.parametrize("transmission", [True, False], ids=["transmitting", "receiving"])
def test_a_hand_at_the_panel_ends_following_and_the_rotor_is_never_turned_back(
    transmission: bool,
) -> None:
    """An attack pass: a transmission period beginning while the operator turned the beam by
    hand took the hand's turn for following's own: it was stopped, and once the transmission
    had ended a new target turned the rotor back to the partner, unasked. The hand ends
    following, as it ends tracking: nothing more is sent, and the rotor stays where the hand
    left it."""
    with spid() as v:
        hand = _turned_by_hand_while_following(v, transmission)
        sent = [f.outcome for f in v.frames(since=hand)]
        assert set(sent) == {"status"}, sent  # polls only: no stop, no target
        assert angle_between(v.truth().az_deg, 300.0) < 1  # where the hand left it
        assert v.status.following is None and v.status.following_ended == "turned by hand"
        assert follow_state(v.status) == "off"  # R/follow/state
        v.heard("W1AW", "FN31")  # a new partner turns nothing either
        v.run_for(60.0)
        assert v.frames("set", since=hand) == [] and angle_between(v.truth().az_deg, 300.0) < 1


@pytest.mark.parametrize("before", ["nothing heard", "no grid heard"])
def test_a_hand_at_the_panel_before_following_has_turned_the_rotor_ends_it_too(
    before: str,
) -> None:
    """Rule 1, a review's gap: following on, the rotor not yet turned to anyone (nothing heard,
    or a status without a grid), the operator turns the beam by hand at the panel. WSJT-X's
    first status naming a partner then turned it away from where the hand left it, a surprise
    move. A hand ends following whenever it is on, as a user's target does."""
    with spid() as v:
        v.follow(True)
        if before == "no grid heard":
            v.heard("JA1ABC", "")  # moves nothing (rule 2)
        v.run_for(5.0)
        hand = v.now
        v.manual_rotate(300.0)  # a hand at the panel
        v.run_until(lambda h: not h.truth().is_moving, 60, "the hand's turn over")
        v.run_for(5.0)
        assert v.status.following is None and v.status.following_ended == "turned by hand"
        assert follow_state(v.status) == "off"  # R/follow/state
        v.heard("JA1ABC", "PM95")  # WSJT-X names a partner
        v.run_for(60.0)
        assert v.frames("set", since=hand) == [] and angle_between(v.truth().az_deg, 300.0) < 1


def test_follow_on_while_locked_is_refused_and_nothing_moves() -> None:
    with spid() as v:
        v.lock(True)
        v.follow(True)
        assert v.status.following is None
        assert v.errors("refused")[-1].message == "rotator is locked"
        v.heard("JA1ABC", "PM95")
        v.run_for(30.0)
        assert sets(v) == 0


def test_a_follow_part_that_raises_is_reset_and_reported_and_the_link_goes_on(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    with spid() as v:
        v.follow(True)

        def broken(self: Follower, scene: Scene) -> None:
            raise RuntimeError("a bug")

        monkeypatch.setattr(Follower, "step", broken)
        v.heard("JA1ABC", "PM95")
        v.run_for(2.0)
        assert v.status.following is None and v.status.following_ended == "internal error"
        assert [e.kind for e in v.errors("internal")] == [ErrorKind.INTERNAL]
        v.target(90.0)
        v.run_until(lambda h: h.state is MotionState.IDLE and h.truth().az_deg > 80, 60, "90")


def test_following_is_activity_auto_park_waits() -> None:
    with spid(park_az_deg=0, park_after_idle_s=30) as v:
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(300.0)
        assert not v.status.parked and angle_between(v.truth().az_deg, bearing("PM95")) <= 0.5
        v.follow(False)
        v.run_until(lambda h: h.status.parked, 120, "parked once following is off")


def test_a_flood_of_other_instance_names_costs_no_memory_and_little_log(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Forged statuses, each naming another instance (a hostile neighbour in the multicast
    group): what following remembers of them stays bounded and the log gets one line per
    IGNORED_LOG_S with the count since, not one per name; the program followed is still
    followed."""
    part = following(rig())
    part.heard(Heard("JA1ABC", "PM95", False, "WSJT-X"), 1.0)
    assert part.step(at(1.0)).target is not None
    caplog.set_level(logging.WARNING, "bridge.session.follow")
    for n in range(20_000):
        part.heard(Heard("W1AW", "FN31", False, f"forged {n} " + "x" * 900), 2.0 + n * 0.001)
    said = [r.getMessage() for r in caplog.records if "is ignored" in r.getMessage()]
    assert len(said) == 1 and len(said[0]) < 300
    assert len(part._ignored) <= fo.IGNORED_KEPT
    part.heard(Heard("W1AW", "FN31", False, "one more"), 2.0 + fo.IGNORED_LOG_S + 1)
    said = [r.getMessage() for r in caplog.records if "is ignored" in r.getMessage()]
    assert len(said) == 2 and "of 19999 other program(s)" in said[1]
    part.heard(Heard("VK2XYZ", "QF56", False, "WSJT-X"), 100.0)  # the one followed
    assert part.step(at(100.0)).target is not None


# -- one antenna per band (rule 9) --------------------------------------------------------------
TWENTY, FORTY = 14_074_000, 7_074_000


def test_a_rotator_with_bands_turns_only_while_the_dial_is_on_one_of_them() -> None:
    part = following(rig(bands=["20m", "15m"]))
    part.heard(Heard("JA1ABC", "PM95", False, dial_hz=FORTY), 1.0)
    off = part.step(at(1.0))
    assert off.target is None and off.error is not None and off.error.kind is ErrorKind.REFUSED
    assert off.error.message == (
        "following: WSJT-X's dial 7.074 MHz is on 40m, and this antenna is for 20m, 15m"
    )
    part.heard(Heard("JA1ABC", "PM95", False, dial_hz=7_047_000), 2.0)  # still 40 m: said once
    again = part.step(at(2.0))
    assert again.target is None and again.error is None
    part.heard(Heard("JA1ABC", "PM95", False, dial_hz=TWENTY), 3.0)  # back on 20 m: turned to
    on = part.step(at(3.0))
    assert on.target is not None and on.target.az_deg is not None
    assert angle_between(on.target.az_deg, bearing("PM95")) < 0.1


def test_a_grid_held_for_a_transmission_that_ended_off_band_is_held_no_more() -> None:
    """Rule 3's ``held`` says a grid waits for a transmission to end: once a status says it
    ended, with the dial off the antenna's bands (rule 9), the grid waits for the band and the
    status says ``held: false`` (it said ``true`` until the dial came back, with nothing on
    the air)."""
    part = following(rig(bands=["20m"]))
    part.heard(Heard("JA1ABC", "PM95", False, dial_hz=TWENTY), 1.0)
    assert part.step(at(1.0)).target is not None
    part.heard(Heard("W1AW", "FN31", True, dial_hz=TWENTY), 2.0)
    assert part.step(at(2.0)).target is None
    assert part.info is not None and part.info.held
    part.heard(Heard("W1AW", "FN31", False, dial_hz=FORTY), 3.0)  # the transmission ended
    off = part.step(at(3.0))
    assert off.target is None and off.error is not None
    assert part.info is not None and not part.info.held
    part.heard(Heard("W1AW", "FN31", False, dial_hz=TWENTY), 4.0)  # back on 20 m: turned to
    on = part.step(at(4.0))
    assert on.target is not None and on.target.az_deg is not None
    assert angle_between(on.target.az_deg, bearing("FN31")) < 0.1


@pytest.mark.parametrize(
    ("dial_hz", "why"),
    [
        (9_000_000, "WSJT-X's dial 9 MHz is on no amateur band"),
        (None, "WSJT-X gave no dial frequency"),
    ],
)
def test_a_rotator_with_bands_does_not_turn_off_every_band(dial_hz: int | None, why: str) -> None:
    part = following(rig(bands=["20m"]))
    part.heard(Heard("JA1ABC", "PM95", False, dial_hz=dial_hz), 1.0)
    proposal = part.step(at(1.0))
    assert proposal.target is None and proposal.error is not None and why in proposal.error.message


def test_a_rotator_without_bands_follows_on_every_band() -> None:
    part = following(rig())
    part.heard(Heard("JA1ABC", "PM95", False, dial_hz=9_000_000), 1.0)
    assert part.step(at(1.0)).target is not None


def test_of_two_antennas_the_one_on_the_dials_band_turns_in_the_session() -> None:
    """Following on for both rotators of a station with one antenna per band: WSJT-X on 40 m
    turns the 40 m antenna alone, then on 20 m the 20 m one alone."""
    with spid(bands=["20m", "15m"]) as high, spid(bands=["40m"]) as low:
        for v in (high, low):
            v.follow(True)
            v.heard("JA1ABC", "PM95", dial_hz=FORTY)
            v.run_for(60.0)
        assert sets(high) == 0 and not high.truth().is_moving
        assert [e.message for e in high.errors("refused")] == [
            "following: WSJT-X's dial 7.074 MHz is on 40m, and this antenna is for 20m, 15m"
        ]
        assert angle_between(low.truth().az_deg, bearing("PM95")) <= 0.5
        for v in (high, low):
            v.heard("VK2XYZ", "QF56", dial_hz=TWENTY)
            v.run_for(60.0)
        assert angle_between(high.truth().az_deg, bearing("QF56")) <= 0.5
        assert angle_between(low.truth().az_deg, bearing("PM95")) <= 0.5  # still on PM95
        assert low.errors("refused")[-1].message.startswith("following: WSJT-X's dial 14.074 MHz")


def test_an_antenna_off_both_radios_bands_says_so_once_not_at_every_status() -> None:
    """SO2R, rig1 on 20 m and rig2 on 40 m, and the 80 m antenna following too: neither radio
    is on its band, and R/error says so once, until a dial comes to 80 m (it said it again at
    every status of each radio, each on another band than the one before: rule 9)."""
    rig1 = Heard("JA1ABC", "PM95", False, "WSJT-X - rig1", TWENTY)
    rig2 = Heard("W1AW", "FN31", False, "WSJT-X - rig2", FORTY)
    with spid(bands=["80m"]) as low:
        low.follow(True)
        for _ in range(4):  # four decoding periods, each radio's status in each
            for heard in (rig1, rig2):
                low.mailbox.put_heard(heard)
                low._take()
                low.run_for(5.0)
        assert [e.message for e in low.errors("refused")] == [
            "following: WSJT-X's dial 14.074 MHz is on 20m, and this antenna is for 80m"
        ]
        assert sets(low) == 0
        on_80 = replace(rig2, dial_hz=3_573_000)  # rig2 comes to 80 m: turned to, and then
        low.mailbox.put_heard(on_80)  # a dial off its band is said again, once
        low._take()
        low.run_for(60.0)
        assert angle_between(low.truth().az_deg, bearing("FN31")) <= 0.5
        for heard in (replace(rig1, grid="QF56"), replace(rig1, grid="QF56", dial_hz=FORTY)):
            low.mailbox.put_heard(replace(heard, instance="WSJT-X - rig2"))
            low._take()
            low.run_for(5.0)
        assert [e.message for e in low.errors("refused")][1:] == [
            "following: WSJT-X's dial 14.074 MHz is on 20m, and this antenna is for 80m"
        ]
        assert angle_between(low.truth().az_deg, bearing("FN31")) <= 0.5


def test_with_two_radios_each_antenna_follows_the_program_on_its_band() -> None:
    """SO2R: one WSJT-X per radio (``--rig-name``), rig1 on 20 m, rig2 on 40 m, both heard by
    both rotators. Each antenna follows the program on its band, whichever spoke first (the
    40 m antenna took rig1's, heard first, and ignored rig2 for as long as it followed)."""
    rig1 = Heard("JA1ABC", "PM95", False, "WSJT-X - rig1", TWENTY)
    rig2 = Heard("W1AW", "FN31", False, "WSJT-X - rig2", FORTY)
    with spid(bands=["20m"]) as high, spid(bands=["40m"]) as low:
        for v in (high, low):
            v.follow(True)
            for heard in (rig1, rig2, rig1, rig2):
                v.mailbox.put_heard(heard)
                v._take()
                v.run_for(5.0)
            v.run_for(60.0)
        assert angle_between(high.truth().az_deg, bearing("PM95")) <= 0.5
        assert angle_between(low.truth().az_deg, bearing("FN31")) <= 0.5


def test_an_antenna_whose_program_left_its_band_follows_the_one_that_came_to_it() -> None:
    """Rule 8 with bands: the 40 m antenna followed rig1 while it was on 40 m; rig1 moved to
    20 m and rig2 came up on 40 m. The 40 m antenna follows rig2 (it kept rig1, now on 20 m,
    and ignored the program on its band until following was switched off and on)."""
    with spid(bands=["40m"]) as low:
        low.follow(True)
        for heard in (
            Heard("W1AW", "FN31", False, "WSJT-X - rig1", FORTY),  # rig1 on 40 m: followed
            Heard("JA1ABC", "PM95", False, "WSJT-X - rig1", TWENTY),  # rig1 to 20 m
            Heard("VK2XYZ", "QF56", False, "WSJT-X - rig2", FORTY),  # rig2 on 40 m
            Heard("JA1ABC", "PM95", False, "WSJT-X - rig1", TWENTY),
            Heard("VK2XYZ", "QF56", False, "WSJT-X - rig2", FORTY),
        ):
            low.mailbox.put_heard(heard)
            low._take()
            low.run_for(30.0)
        low.run_for(60.0)
        assert angle_between(low.truth().az_deg, bearing("QF56")) <= 0.5


def test_the_status_names_the_program_it_listens_to_and_none_while_it_takes_the_first() -> None:
    """Rule 8 as the status says it (``following.instance``, not published: the WSJT-X
    listener keeps budget room for that program's statuses, interfaces/wsjtx/server.py rule
    5): none before a program is heard on its band, the first heard on it, none again when it
    left the band (the first heard on it next is followed), the one come to it, none once
    following ends."""
    with spid(bands=["40m"]) as low:
        low.follow(True)
        low.run_for(2.0)
        said: list[str | None] = []
        for heard in (
            Heard("W1AW", "FN31", False, "WSJT-X - rig1", FORTY),  # rig1 on 40 m: followed
            Heard("JA1ABC", "PM95", False, "WSJT-X - rig1", TWENTY),  # rig1 to 20 m
            Heard("VK2XYZ", "QF56", False, "WSJT-X - rig2", FORTY),  # rig2 on 40 m
        ):
            assert low.status.following is not None
            said.append(low.status.following.instance)
            low.mailbox.put_heard(heard)
            low._take()
            low.run_for(5.0)
        assert low.status.following is not None
        said.append(low.status.following.instance)
        assert said == [None, "WSJT-X - rig1", None, "WSJT-X - rig2"]
        low.follow(False)
        low.run_for(2.0)
        assert low.status.following is None


def test_switched_on_the_antenna_turns_at_once_to_the_qso_under_way_on_its_band() -> None:
    """Rule 4 with bands and two radios: rig2 on 40 m named FN31, then rig1 on 20 m spoke last.
    Switched on, the 40 m antenna turns at once to FN31, the QSO under way on its band (it said
    rig1's 20 m dial was not for it on R/error, and waited for rig2's next status)."""
    with spid(bands=["40m"]) as low:
        for heard in (
            Heard("W1AW", "FN31", False, "WSJT-X - rig2", FORTY),
            Heard("JA1ABC", "PM95", False, "WSJT-X - rig1", TWENTY),
        ):
            low.mailbox.put_heard(heard)
            low._take()
            low.run_for(2.0)
        low.follow(True)
        low.run_for(60.0)
        assert angle_between(low.truth().az_deg, bearing("FN31")) <= 0.5
        assert low.errors("refused") == []


def test_a_turn_under_way_is_not_stopped_by_a_transmission_on_another_band() -> None:
    """Rule 9: a turn under way when the band changes is not stopped (it was for the partner
    heard on its band). An attack pass: the 20 m antenna turning to PM95, WSJT-X moved to 40 m
    and transmitted there at once: hold-while-TX stopped the 20 m antenna half way, and with
    the dial off its bands nothing ever turned it on, left pointing at neither."""
    with spid(bands=["20m"]) as v:
        v.follow(True)
        v.heard("JA1ABC", "PM95", dial_hz=TWENTY)
        v.run_for(1.5)
        assert v.truth().is_moving
        v.heard("JA1ABC", "PM95", True, dial_hz=FORTY)  # on 40 m, transmitting on the other antenna
        v.run_for(12.6)
        v.heard("JA1ABC", "PM95", False, dial_hz=FORTY)
        v.run_until(lambda h: h.state is MotionState.IDLE and not h.truth().is_moving, 60, "")
        assert angle_between(v.truth().az_deg, bearing("PM95")) <= 0.5


def test_a_transmission_start_is_not_lost_beside_another_programs_status_in_one_batch() -> None:
    """Two WSJT-X instances (SO2R, or a second station in the multicast group) send their
    statuses at the same period boundaries, so both can land in one mailbox batch before the
    serial-lines thread takes it. The followed instance's "transmitting" must not be replaced
    by the other's status: the turn stops while it transmits, as with one program (the
    mailbox kept only the newest status, the other's, and the beam kept turning through the
    transmission)."""
    with spid() as v:
        v.follow(True)
        v.mailbox.put_heard(Heard("JA1ABC", "PM95", False, "WSJT-X - 20m"))
        v._take()
        v.run_for(1.5)
        assert v.truth().is_moving
        v.mailbox.put_heard(Heard("JA1ABC", "PM95", True, "WSJT-X - 20m"))  # it transmits
        v.mailbox.put_heard(Heard("W1AW", "FN31", False, "WSJT-X - 6m"))  # the other decodes
        v._take()
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "the turn stopped")
        where = v.truth().az_deg
        assert angle_between(where, bearing("PM95")) > 5  # stopped on the way
        assert v.status.following is not None and v.status.following.held


# -- what WSJT-X names, as shown (rule 10) -----------------------------------------------
@pytest.mark.parametrize(
    "call",
    [
        "K1ABC\n2026-01-01 00:00:00 CRITICAL bridge: rotator 'hf' lock OFF",  # a forged log line
        "K" * 300,  # past Home Assistant's longest state (255): its sensor refuses every status
        "K1ABC\x1b[2J",  # a terminal's escape (a journal read with less -R, a console)
        "K1ABC\u2028forged",  # a line separator: a line end to a viewer that honours it
        "\u202eCBA1K",  # a right-to-left override: the log's text read backwards
    ],
)
def test_a_dx_call_that_is_no_call_sign_is_not_shown_nor_logged_and_the_grid_still_turns(
    call: str, caplog: pytest.LogCaptureFixture
) -> None:
    """WSJT-X's DX call comes from whoever can reach its UDP port (a program on this computer,
    the multicast group's other members, the LAN with ``bind = 0.0.0.0``): up to a kilobyte of
    any text. It was shown as the followed station (``R/status``, Home Assistant's sensor) and
    written into the log as sent: a line end forged log lines, and a call longer than 255
    characters made Home Assistant refuse the sensor's state at every status. A call with a
    control character or longer than any call sign is shown as none; its grid is followed as
    before (the grid, not the call, is what the rotor turns to)."""
    caplog.set_level(logging.INFO, "bridge.session.follow")
    part = following(rig())
    part.heard(Heard(call, "PM95", False), 1.0)
    proposal = part.step(at(1.0))
    assert proposal.target is not None and proposal.target.az_deg is not None
    assert angle_between(proposal.target.az_deg, bearing("PM95")) < 0.1
    assert part.info is not None and part.info.call is None and part.info.grid == "PM95"
    logged = [r.getMessage() for r in caplog.records]
    assert logged and all(call not in line and "\n" not in line for line in logged)
    assert all(len(line) < 200 for line in logged)


def test_a_refusal_names_a_real_call_and_no_junk() -> None:
    """The R/error of a grid the judge refuses names the call as the status does (rule 10)."""
    east, west = bearing("PM95"), bearing("FN31")
    part = following(rig(keep_out=[[east - 10.0, east + 10.0], [west - 10.0, west + 10.0]]))
    part.heard(Heard("JA1ABC\r\nforged", "PM95", False), 1.0)
    error = part.step(at(1.0)).error
    assert error is not None and error.command == "follow ? PM95"
    part.heard(Heard(" W1AW ", "FN31", False), 2.0)
    error = part.step(at(2.0)).error
    assert error is not None and error.command == "follow W1AW FN31"
