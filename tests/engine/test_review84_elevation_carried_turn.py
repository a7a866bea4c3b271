"""Review 84 (429ed454: parts.py rule 10, ``StartHalt.owed``; motion.py rule 4,
``carried_seen_s``): a start refused right after a replug mid-turn owes the halt to the turn the
controller goes on with, and drops it once readings back for ``carried_seen_s`` show no move
(``lost_still``). But ``carried_seen_s`` is timed at the azimuth's nominal speed alone
(``cfg.nominal_speed_deg_s``), and an elevation turns slower (a GS-232's 2.5 deg/s against 6,
read in whole degrees with 2 degrees of noise): an elevation-only turn carried over the replug
has not moved past the noise by then, is taken for a turn that ended unplugged, the owed halt is
dropped, and the elevation turns on to the target from before the unplug (observed 26 -> 85)
while R/error says the follow start was refused. The same turn without the replug is halted."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from tests.engine.test_attack19_follow_start_refused_grid import PARTNER
from tests.engine.test_follow import STATION
from tests.engine.virtual import VirtualRotator

START_AZ = round(PARTNER) + 20  # (attack 19's set-up: 20 degrees past the keep-out sector)


def gs232_azel_by_a_keep_out() -> VirtualRotator:
    """A GS-232B az/el, following the test station's partners, a keep-out sector 10 degrees
    either side of PARTNER's bearing and the rotor pointing 20 degrees past it, at the horizon."""
    sector = [round(PARTNER) - 10, round(PARTNER) + 10]
    return VirtualRotator(
        "gs232b",
        emulator={"start_az_deg": START_AZ, "start_el_deg": 0},
        follow=STATION,
        settings={"keep_out": [sector]},
    )


def raising_the_elevation(v: VirtualRotator) -> None:
    """At rest, its brake delay over, then told to raise the elevation alone to 85 degrees."""
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
    v.run_for(6.0)  # the brake delay after its start is over (not a deadline)
    v.target(START_AZ, 85.0)
    v.run_until(lambda h: h.truth().el_deg >= 20.0, 60, "the elevation turning")


def test_a_refused_follow_start_right_after_a_replug_halts_the_carried_elevation_turn() -> None:
    with gs232_azel_by_a_keep_out() as v:
        raising_the_elevation(v)
        v.run_for(0.1)  # (between two polls: a query torn by the unplug is another story)
        v.link_down()
        v.run_for(2.0)  # (the adapter out: not a deadline)
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers again")
        assert v.truth().is_moving  # it finishes its old turn by itself
        t, here = v.now, v.truth().el_deg
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the old target is some 25 s on: not a deadline)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        assert v.status.following is not None  # taken, and waiting for a grid it may turn to
        # held where it was (a stop and its coast), as without the replug: observed 26 -> 85
        assert abs(v.truth().el_deg - here) <= 10.0, (here, v.truth().el_deg)
        assert "stop" in {f.outcome for f in v.frames(since=t)}


def test_the_same_refused_start_without_a_replug_halts_the_elevation_turn() -> None:
    """The control: the elevation turn seen with the link up is halted by the refusal."""
    with gs232_azel_by_a_keep_out() as v:
        raising_the_elevation(v)
        t, here = v.now, v.truth().el_deg
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the old target is some 25 s on: not a deadline)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        assert abs(v.truth().el_deg - here) <= 10.0, (here, v.truth().el_deg)
