"""Review 70 (968c2d20, 9890fe96: parts.py rule 10, ``StartHalt``): a start whose first target
the judge refuses holds the rotor where it is, the turn under way stopped once, and that turn
may be the one a controller finishes by itself after a replug mid-turn (parts.py rule 8,
review 50's case: the start's first target stops it or re-targets it). But ``turning`` leaves
out a turn carried over the lost link that no reading has shown moving since (motion.py rule
4, ``lost_turning``), and the two refusals attack 19 fixed are judged once and never again:
following's grid ("reported once for that grid and not tried again", follow.py rule 5) and
tracking's wait for the pass (``_waited_for`` is set before the judge). A start right after the
controller answers again is refused on R/error, nothing halts, and the rotor turns on some 95
degrees to the target from before the unplug, which nobody stands for any more. (A refused
step mid-pass is judged again at every step and halts the turn once it is seen: not this.)"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from bridge.sky import Body
from tests.engine.test_attack19_follow_start_refused_grid import (
    PARTNER,
    follower_by_a_keep_out,
    turning_away_from_the_partner,
)
from tests.engine.test_attack19_track_start_refused_wait import (
    T0,
    rotorez_under_a_kept_out_pass,
    turning_toward_340,
)
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between
from tests.support.sky import synthetic_tle


def replugged_mid_turn(v: VirtualRotator) -> None:
    """The adapter pulled and put back while the rotor turns; the controller answers again,
    finishing its old turn by itself (its target dropped with the port)."""
    v.run_for(0.1)  # (between two polls: a query torn by the unplug is another story)
    v.link_down()
    v.run_for(2.0)  # (the adapter out: not a deadline)
    v.link_up()
    v.run_until(lambda h: h.status.available, 10, "the controller answers again")
    assert v.truth().is_moving  # (it finishes its old turn by itself)


def rotorez_turning_away_from_the_partner(v: VirtualRotator) -> None:
    """A Rotor-EZ answering, seen at rest, its start's brake delay over, then turning away from
    PARTNER (attack 19's set-up)."""
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
    v.run_for(6.0)  # the Rotor-EZ's brake delay after its start is over
    turning_away_from_the_partner(v)


def a_follow_start_refused_after(
    v: VirtualRotator, interrupted: Callable[[VirtualRotator], None]
) -> tuple[float, float]:
    """A Rotor-EZ turning away from PARTNER, ``interrupted`` mid-turn (a replug, a restart);
    a follow start refused at once for the keep-out, a minute on. When it was asked and the
    azimuth then."""
    rotorez_turning_away_from_the_partner(v)
    interrupted(v)
    t, here = v.now, v.truth().az_deg
    v.follow(True)
    v.heard("JA1ABC", "PM95")
    v.run_for(60.0)  # (the old target is some 15 s on: not a deadline)
    [refused] = v.errors(ErrorKind.REFUSED, since=t)
    assert "keep-out" in refused.message
    return t, here


def a_track_started_after(
    v: VirtualRotator, interrupted: Callable[[VirtualRotator], None]
) -> tuple[float, float]:
    """A Rotor-EZ under a kept-out pass turning toward 340, ``interrupted`` mid-turn; a track
    of the pass started at once, a minute on. When it was asked and the azimuth then."""
    line1, line2 = synthetic_tle(
        "TESTSAT", T0, inclination_deg=97.5, raan_deg=0.0, mean_anomaly_deg=0.0
    )
    turning_toward_340(v)
    interrupted(v)
    t, here = v.now, v.truth().az_deg
    v.track(Body.satellite("TESTSAT", line1, line2))
    v.run_for(60.0)  # (the old target is some 20 s on: not a deadline)
    return t, here


def test_a_refused_follow_start_right_after_a_replug_mid_turn_holds_the_rotor() -> None:
    with follower_by_a_keep_out("rotorez") as v:
        t, here = a_follow_start_refused_after(v, replugged_mid_turn)
        assert v.status.following is not None  # taken, and waiting for a grid it may turn to
        # held where it was (a stop and the Rotor-EZ's coast): observed 90 -> 182
        assert angle_between(v.truth().az_deg, here) <= 15.0, (here, v.truth().az_deg)


def test_a_track_start_whose_wait_is_refused_right_after_a_replug_mid_turn_holds_the_rotor() -> (
    None
):
    with rotorez_under_a_kept_out_pass() as v:
        t, here = a_track_started_after(v, replugged_mid_turn)
        assert v.status.tracking is not None  # taken, and holding
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message and "holding" in refused.message
        # held where it was (a stop and the Rotor-EZ's coast): observed 244 -> 340
        assert abs(v.truth().az_deg - here) <= 15.0, (here, v.truth().az_deg)


def test_a_refused_follow_start_after_a_replug_whose_turn_ended_unplugged_halts_no_hand() -> None:
    """The halt owed to the carried turn is dropped once that turn is known to be none (the
    rotor came to rest while its port was out: no stop to it, motion.py rule 4), so a hand at
    the panel afterwards is never halted as the bridge's turn (reviews 52, 53)."""
    with follower_by_a_keep_out("rotorez") as v:
        rotorez_turning_away_from_the_partner(v)
        v.link_down()
        v.run_until(lambda h: not h.truth().is_moving, 60, "the old turn over, unplugged")
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers again")
        t = v.now
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_until(lambda h: bool(h.errors(ErrorKind.REFUSED, since=t)), 10, "refused")
        v.run_until(lambda h: not h.status.moving, 30, "seen at rest")
        v.run_for(5.0)  # (a few polls at rest: not a deadline)
        hand_to = round(PARTNER + 60.0)  # (never through the sector)
        v.manual_rotate(hand_to)  # a hand at the panel
        v.run_until(lambda h: h.status.moving, 10, "the bridge sees the hand's turn")
        v.run_until(lambda h: not h.truth().is_moving, 90, "the hand's turn over")
        assert {f.outcome for f in v.frames(since=t)} == {"query"}  # no stop: none owed
        assert angle_between(v.truth().az_deg, hand_to) <= 1.0  # where the hand left it
