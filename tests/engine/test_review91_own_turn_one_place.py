"""One park of the bridge's own takes one place in the order of commands however often it
begins (session/mailbox.py rule 10b, runtime/composite.py rule 10; review 91): R/status's
``order.turn`` names it once, so a remote's STOP asked against it is never read as overtaken by
the park itself (interfaces/mqtt/remote.py rule 10). A park begun after a command or a halt, or
another storm's, is a turn of its own and takes a later place: a STOP held from before it never
stops it. In virtual time (tests/engine/virtual.py); the statuses are R/status's."""

from __future__ import annotations

from bridge.core.model import MotionState, RotatorStatus, Source, Stop, Target
from bridge.session.mailbox import Mailbox
from bridge.session.session import OwnTurn
from tests.engine.test_wind_park_offline import FAST, WIND, at_10_30, storm
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite

CALM = {**WIND, "wind_release_below": 40, "wind_hold_min": 1}


def turns(statuses: list[tuple[float, RotatorStatus]], after: int) -> set[int]:
    """The places the statuses name as their turn past place ``after``."""
    return {s.order.turn for _, s in statuses if s.order is not None and s.order.turn > after}


def at_rest(v: VirtualRotator) -> None:
    """A GS-232B at rest at 10 / 30 (its wind park at 180 / 0), as test_wind_park_offline has
    it."""
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
    v.target(10.0, 30.0)
    v.run_until(lambda h: abs(h.truth().az_deg - 10) < 1, 120, "at 10")


def taken(status: RotatorStatus) -> int:
    assert status.order is not None
    return status.order.taken


def test_a_storm_park_sent_again_once_the_controller_answers_keeps_its_one_place() -> None:
    """A GS-232B falls silent two seconds into its storm's park (stopped at the offline) and
    answers again: the park owed goes again (wind.py rule 7), the same turn at the same place
    (before: a second ticket, places 2 and 3 with no command between)."""
    v = VirtualRotator("gs232b", settings=WIND, emulator={"az_speed_deg_s": 6.0}, own_places=True)
    try:
        at_rest(v)
        before, seen = taken(v.status), len(v.statuses)
        storm(v)
        assert v.truth().is_moving
        v.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "offline")
        v.set_silent(False)
        v.run_until(lambda h: h.status.available, 20, "back")
        v.run_until(
            lambda h: abs(h.truth().az_deg - 180.0) < 1.0 and abs(h.truth().el_deg) < 1.0,
            180,
            "at its park, sent again",
        )
        assert turns(v.statuses[seen:], before) == {before + 1}
    finally:
        v.close()


def test_a_composites_park_in_a_new_storm_takes_a_later_place_than_the_last_storms() -> None:
    """The elevation box out through a storm that parks the azimuth alone, a calm, and a new
    storm it is plugged back in: the new storm's park is a turn of its own, past every place the
    first storm's statuses showed (a STOP asked against the first park, held by a remote, is
    then never read as asked against the second), and still one place for both boxes."""
    with VirtualComposite("rt21", "gs232b", settings=CALM, emulators=FAST) as v:
        at_10_30(v)
        v.el.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "the elevation box out")
        v.mailbox.put_wind(90.0)
        v._take()
        v.run_until(lambda h: abs(h.az.truth().az_deg - 180.0) < 1.0, 60, "azimuth parked")
        calm(v)
        first, seen = max(taken(s) for _, s in v.statuses), len(v.statuses)
        v.mailbox.put_wind(90.0)
        v._take()
        v.el.set_silent(False)
        v.run_until(
            lambda h: h.status.available and abs(h.el.truth().el_deg) < 1.0, 120, "dish down"
        )
        assert turns(v.statuses[seen:], first) == {first + 1}


def test_one_turn_keeps_its_place_until_a_motion_command_or_a_halt_is_put_after_it() -> None:
    """mailbox.py rule 10b itself: the same storm's park named again keeps its place across a
    lock OFF (no turn, no halt), and takes a later one after a target or a STOP put since, as
    another storm's park does."""
    storm_1, storm_2 = OwnTurn(Source.WIND, 1), OwnTurn(Source.WIND, 2)
    mailbox = Mailbox()
    try:
        place = mailbox.own_place(storm_1)
        assert mailbox.own_place(storm_1) == place  # (the other box, or once it answers)
        mailbox.put_lock(False)
        assert mailbox.own_place(storm_1) == place
        assert mailbox.own_place(storm_2) > place  # another storm's park: its own turn
        place = mailbox.own_place(storm_2)
        mailbox.put(Target(100.0, 20.0))  # (a target put after the park began...)
        after_target = mailbox.own_place(storm_2)
        assert after_target > place  # (...makes a park begun after it a later turn)
        mailbox.put(Stop())
        assert mailbox.own_place(storm_2) > after_target + 1  # (past the STOP's place too)
    finally:
        mailbox.close()


def calm(v: VirtualRotator | VirtualComposite) -> None:
    """Calm readings for longer than wind_hold_min: the storm is over."""
    for _ in range(3):
        v.mailbox.put_wind(10.0)
        v._take()
        v.run_for(40.0)
    assert v.status.wind is not None and not v.status.wind.storm


def test_a_new_storms_park_takes_a_later_place_than_the_last_storms() -> None:
    """One controller parked for a storm, a calm, a new storm: its park is a turn of its own,
    past every place the first storm's statuses showed, though nothing was put between (a STOP
    asked against the first park and held by a remote never stops the second)."""
    v = VirtualRotator("gs232b", settings=CALM, emulator={"az_speed_deg_s": 6.0}, own_places=True)
    try:
        v.run_until(lambda h: h.status.available, 60, "ready")
        storm(v)
        v.run_until(lambda h: abs(h.truth().az_deg - 180.0) < 1.0, 120, "parked")
        calm(v)
        first, seen = max(taken(s) for _, s in v.statuses), len(v.statuses)
        storm(v)
        v.run_for(5.0)
        assert turns(v.statuses[seen:], first) == {first + 1}
    finally:
        v.close()
