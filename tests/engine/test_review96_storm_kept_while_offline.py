"""Review 96: a controller that does not answer through a calm keeps the storm it had, and the
next storm is taken for it. session/wind.py rule 2 ends a storm by the readings (below the
release level for ``wind_hold_min``), but the end is judged only at the part's steps, which run
only while the controller answers (WindPark.step); the readings of the calm and of the next
storm are taken meanwhile, the next storm's first reading starts the hold again, and once the
controller answers the first storm is still on: its STOP (wind.py rule 3: no park again in
*that* storm) holds back the new storm's park, and the new storm's park is named by the old
storm's number (mailbox.py rule 10b, session.py ``_own_turn``), at the old storm's place.

What a user sees:
- one controller, STOPped in the first storm, switched off or silent through a calm of minutes
  and back in the next storm: the park is never sent in the new storm (the rotor stands where
  the STOP left it), R/error says "a stop or lock ON stopped its park";
- the same without the STOP: the new storm's park shows the first storm's place in R/status
  ``order.turn``, so a remote's STOP held from the first storm (interfaces/mqtt/remote.py rule
  10) is read as asked against it, goes again and stops the new storm's park for that whole
  storm (before, with the controller answering, a new storm's park takes a later place:
  test_review91_own_turn_one_place.py);
- a two-box rotator whose elevation box was unplugged through the calm: the azimuth box sees
  the storm end and the next begin (runtime/composite.py rule 10, f96b859a, names the box's park
  by the rotator's newest storm for its place, but the box's wind state stays the old storm's),
  and the operator's STOP in the first storm is still the elevation box's when it is plugged
  back in the second: the dish stands raised at 30 degrees for the whole storm while R/status
  says "parked for the storm".

In virtual time (tests/engine/virtual.py; virtual_composite.py serves the boxes as
CompositeWorker does)."""

from __future__ import annotations

from tests.engine.test_review91_own_turn_one_place import CALM, at_rest, calm, taken, turns
from tests.engine.test_wind_park_offline import FAST, at_10_30
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite


def calm_while_silent(v: VirtualRotator) -> None:
    """The controller silent; calm readings for two minutes (past wind_hold_min: by rule 2 the
    storm is over); the next storm's first reading; the controller answers again."""
    v.set_silent(True)
    v.run_until(lambda h: not h.status.available, 10, "offline")
    for _ in range(3):
        v.mailbox.put_wind(10.0)
        v._take()
        v.run_for(40.0)
    v.mailbox.put_wind(90.0)
    v._take()
    v.run_for(5.0)
    v.set_silent(False)
    v.run_until(lambda h: h.status.available, 20, "back")


def test_the_next_storms_park_goes_though_the_last_storm_was_stopped_before_a_silence() -> None:
    """A GS-232B at 10 / 30, its wind park 180 / 0: a storm, its park STOPped 3 s in; the
    controller silent through a calm of two minutes and the next storm's first reading: once it
    answers, the new storm's park goes and the rotor ends at 180."""
    v = VirtualRotator("gs232b", settings=CALM, emulator={"az_speed_deg_s": 6.0}, own_places=True)
    try:
        at_rest(v)
        v.mailbox.put_wind(90.0)
        v._take()
        v.run_for(3.0)
        v.stop()
        v.run_for(5.0)
        short = v.truth().az_deg
        assert abs(short - 180.0) > 20.0, short  # (stopped short of the first park)
        calm_while_silent(v)
        v.run_for(120.0)
        assert abs(v.truth().az_deg - 180.0) < 1.0, v.truth()
    finally:
        v.close()


def test_the_next_storms_park_after_a_silent_calm_takes_a_later_place() -> None:
    """A GS-232B parking for a storm falls silent 3 s in (its park owed: wind.py rule 7); a calm
    of two minutes and the next storm's first reading come while it is silent; once it answers
    the park goes (to 180), a turn of the new storm: at a place past every place the first
    storm's statuses showed."""
    v = VirtualRotator("gs232b", settings=CALM, emulator={"az_speed_deg_s": 6.0}, own_places=True)
    try:
        at_rest(v)
        v.mailbox.put_wind(90.0)
        v._take()
        v.run_for(3.0)
        first = max(taken(s) for _, s in v.statuses)  # (the first storm's places, before the
        calm_while_silent(v)  # silence: the status that shows it back may show the new park)
        v.run_until(lambda h: abs(h.truth().az_deg - 180.0) < 1.0, 120, "parked")
        assert turns(v.statuses, first) == {first + 1}
    finally:
        v.close()


def test_a_stop_in_one_storm_does_not_hold_back_the_next_storms_park_on_a_replugged_box() -> None:
    """RT-21 azimuth, GS-232B elevation at 10 / 30 (the wind park 180 / 0); the elevation box
    unplugged; a storm, its park stopped by the operator 3 s in; a calm ends the storm; a new
    storm parks the azimuth at 180; the elevation box is plugged back in it: the dish goes down
    to 0, as it would have with both boxes answering."""
    with VirtualComposite("rt21", "gs232b", settings=CALM, emulators=FAST) as v:
        at_10_30(v)
        v.el.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "the elevation box out")
        v.mailbox.put_wind(90.0)
        v._take()
        v.run_for(3.0)
        v.stop()  # (the first storm's park stopped: none again in that storm)
        v.run_for(10.0)
        calm(v)
        v.mailbox.put_wind(90.0)  # (the second storm)
        v._take()
        v.run_until(lambda h: abs(h.az.truth().az_deg - 180.0) < 1.0, 60, "azimuth parked")
        assert v.status.wind is not None and v.status.wind.storm and not v.status.wind.halted
        v.el.set_silent(False)
        v.run_for(120.0)
        assert v.el.status.available
        assert abs(v.el.truth().el_deg) < 1.0, v.el.truth()
