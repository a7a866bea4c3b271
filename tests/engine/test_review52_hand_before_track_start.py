"""Review 52 (cold review of d49f9a16, parts.py rule 8's ``Before``): a hand at the front panel
while tracking ends tracking (tracking.py rule 1), and the rotor stays where the hand leaves it.
``Before`` was meant for the turn a controller finishes by itself after a replug mid-turn (its
target dropped with the port, motion.py rule 4), but it takes any turn with no target and no
stop out that the part's first step sees: a hand's turn too, one the bridge watched begin at
rest with the link up and no target of its own anywhere. The operator at the panel turning the
beam when ``track sun`` arrives (another console, a script) is no longer a hand: tracking stays
on, and its first target stops the hand's turn and turns the antenna back to the sun (before
d49f9a16: "turned by hand", the rotor left where the hand took it). With the sun refused (a
keep-out sector), tracking's refused-first-step halt (7447112e) stops the hand's turn instead.
What a user notices: the antenna he is turning by hand is stopped, and turned away from him."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import NamedTuple

import pytest

from bridge.sky import Body, Sky
from tests.engine.test_follow import spid
from tests.engine.test_session_tracking import SUN_EPOCH, off_deg, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between
from tests.support.sky import sun_altaz


class Beside(NamedTuple):
    v: VirtualRotator
    sun_az: float
    away: float  # 120 degrees from the sun, never across north
    toward: float  # the side of the sun the rotor starts on (20 degrees, signed)


@contextlib.contextmanager
def beside_the_sun(keep_out_sun: bool = False, settled: bool = True) -> Iterator[Beside]:
    """A Rotor-EZ 20 degrees from the sun, answering; ``settled``: at rest, its start-up brake
    delay over; ``keep_out_sun``: the sun in a keep-out sector (never between the two)."""
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    sun_az = sun_altaz(lat, lon, wall)[0]
    away = sun_az - 120.0 if sun_az > 180.0 else sun_az + 120.0  # never across north
    toward = 20.0 if away > sun_az else -20.0  # (never through the sector)
    emulator = {"start_az_deg": round(sun_az + toward)}
    settings = {"keep_out": [[round(sun_az) - 10, round(sun_az) + 10]]} if keep_out_sun else {}
    with VirtualRotator(
        "rotorez", sky=Sky(lat, lon), wall_epoch_s=wall, emulator=emulator, settings=settings
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        if settled:
            v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
            v.run_for(6.0)  # the Rotor-EZ's brake delay after its start is over
        yield Beside(v, sun_az, away, toward)


@pytest.mark.parametrize("sun", ["allowed", "in a keep-out sector"])
def test_a_hand_turning_the_rotor_when_tracking_starts_ends_tracking_and_is_not_stopped(
    sun: str,
) -> None:
    with beside_the_sun(keep_out_sun=sun != "allowed") as (v, sun_az, away, toward):
        v.manual_rotate(round(away))  # a hand at the panel
        v.run_until(lambda h: h.status.moving, 10, "the bridge sees the hand's turn")
        hand = v.now
        v.track(Body.sun())
        v.run_until(lambda h: not h.truth().is_moving, 60, "the rotor at rest")
        v.run_for(30.0)
        sent = {f.outcome for f in v.frames(since=hand)}
        assert sent == {"query"}, sent  # polls only; observed: a stop, and the sun's bearing
        assert off_deg(v.truth().az_deg, round(away)) <= 1.0  # where the hand left it
        assert v.status.tracking is None and v.status.tracking_ended == "turned by hand"


def test_a_hand_turning_the_rotor_when_following_starts_ends_following() -> None:
    """Following (follow.py rule 1) takes the same ``Before``: ``R/follow`` on while the
    operator turns the beam by hand at the panel, then WSJT-X names a partner: the rotor is
    stopped and turned to the partner (before d49f9a16: "turned by hand", nothing sent)."""
    with spid() as v:
        v.run_for(5.0)
        v.manual_rotate(300.0)  # a hand at the panel
        v.run_until(lambda h: h.status.moving, 10, "the bridge sees the hand's turn")
        hand = v.now
        v.follow(True)
        v.run_for(2.0)  # (the hand's turn goes on: not a deadline)
        v.heard("JA1ABC", "PM95")  # WSJT-X names a partner
        v.run_until(lambda h: not h.truth().is_moving, 60, "the rotor at rest")
        v.run_for(30.0)
        assert v.frames("set", since=hand) == []  # observed: the partner's bearing
        assert angle_between(v.truth().az_deg, 300.0) < 1  # where the hand left it
        assert v.status.following is None and v.status.following_ended == "turned by hand"


def test_a_hand_after_a_replugged_turn_came_to_rest_is_a_hand_at_a_tracking_start() -> None:
    """The turn carried over a lost link (motion.py rule 4) is no hand only until it rests: a
    replug mid-turn, the rotor at rest at its target, then a hand at the panel and ``track
    sun``: tracking ends "turned by hand", nothing but polls goes out, and the rotor stays where
    the hand left it (review 53's first question of ``Motion.carried``)."""
    with beside_the_sun() as (v, sun_az, away, toward):
        v.target(round(sun_az + 2 * toward))  # a short turn
        v.run_until(lambda h: h.truth().is_moving, 10, "turning")
        v.link_down()
        v.run_for(1.0)  # (the adapter out: not a deadline)
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers again")
        v.run_until(lambda h: not h.truth().is_moving and not h.status.moving, 60, "at rest")
        v.run_for(10.0)  # (its brake delay over: not a deadline)
        v.manual_rotate(round(away))  # a hand at the panel
        v.run_until(lambda h: h.status.moving, 10, "the bridge sees the hand's turn")
        hand = v.now
        v.track(Body.sun())
        v.run_until(lambda h: not h.truth().is_moving, 90, "the rotor at rest")
        v.run_for(30.0)
        assert {f.outcome for f in v.frames(since=hand)} == {"query"}
        assert off_deg(v.truth().az_deg, round(away)) <= 1.0  # where the hand left it
        assert v.status.tracking is None and v.status.tracking_ended == "turned by hand"
