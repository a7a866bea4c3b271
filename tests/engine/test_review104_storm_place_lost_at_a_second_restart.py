"""Review 104: the place a storm's park took (``storm_place``, runtime/kept.py rule 4) survives
one restart only. Every run's first status is the session's bare one (``RotatorSession.start``:
no ``wind`` yet), and runtime/rotator.py hands every status to Kept: ``seen_wind(None)`` reads
as the storm over, so Kept drops the kept place (a storm begun: ``storm_place = 0``) and saves
the storm ended; the next status says the storm again, and Kept saves it with no place. The
park the new run sends again is at the kept place (mailbox.py rule 10b), which is not past
Kept's ``since`` (the storm's start as Kept saw it), so no status gives the place back.

What a user sees: an operator pressed STOP against the storm's park (stamped with the place
R/status showed, the park's); the station's power blinks twice (the bridge restarts mid-park
twice): after the second restart the park shows a place of the new run, past the stamp, the
remote's held STOP (interfaces/mqtt/remote.py rule 10) is read as older than it and dropped,
and the rotor turns on to the park though the operator stopped it: review 96's High, back at
the second restart. In virtual time, with the real state file fed every status as
runtime/rotator.py feeds it, each run's places as runtime/rotator.py starts them."""

from __future__ import annotations

from pathlib import Path

from bridge.core.model import MotionState, RotatorStatus
from bridge.interfaces.mqtt.remote import held_stamp
from bridge.session.mailbox import Mailbox
from tests.engine.kept_storm import kept, saved, session_from
from tests.engine.test_wind_park_offline import WIND, storm
from tests.engine.virtual import VirtualRotator


def restart(v: VirtualRotator, path: Path, begun: int) -> int:
    """The bridge dies mid-park (the run's statuses from ``begun`` saved) and starts again
    from the state file as runtime/rotator.py starts it; returns where the new run begins."""
    saved(v, path, begun, timed=True)
    v.power_cycle()
    v.link_down(None)
    v.run_for(1.0)
    again = kept(v, path)
    v.mailbox.close()
    v.mailbox = Mailbox()
    v.mailbox.places_after(again.since)
    v.session = session_from(v, again, place=v.mailbox.own_place)
    begun = len(v.statuses)
    v._do(v.session.start(v.now))
    v.link_up()
    return begun


def turns(statuses: list[RotatorStatus]) -> set[int]:
    return {s.order.turn for s in statuses if s.order is not None and s.order.turn}


def test_a_storm_park_keeps_its_place_across_two_restarts(tmp_path: Path) -> None:
    """A GS-232B at rest at 10 / 30; a storm; two seconds into the park the bridge dies and
    starts again in the storm (the park goes again, at its place: review 96's fix); two
    seconds later it dies again and starts again: the park still shows the place the first
    run showed, so a remote's STOP pressed against it still stands."""
    path = tmp_path / "state.json"
    v = VirtualRotator("gs232b", settings=WIND, emulator={"az_speed_deg_s": 6.0}, own_places=True)
    try:
        v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
        v.target(10.0, 30.0)
        v.run_until(lambda h: abs(h.truth().az_deg - 10) < 1, 120, "at 10")
        seen = len(v.statuses)
        storm(v)
        assert v.truth().is_moving
        first = turns(v.published()[seen:])
        assert len(first) == 1, first  # (the park's one place)
        before: dict[str, tuple[int, ...]] = {}  # a remote's STOP pressed now, held
        for s in v.published():
            if s.order is not None:
                before[s.order.run] = (*before.get(s.order.run, ()), s.order.taken)
        second = restart(v, path, 0)
        v.run_for(2.0)
        assert v.truth().is_moving  # (the park sent again by the second run)
        assert turns(v.published()[second:]) == first  # (review 96's fix holds once)
        third = restart(v, path, second)
        v.run_until(
            lambda h: abs(h.truth().az_deg - 180.0) < 1.0 and abs(h.truth().el_deg) < 1.0,
            180,
            "at its park, sent again by the third run",
        )
        again = [s for s in v.published()[third:] if s.order is not None and s.order.turn]
        assert turns(again) == first
        for s in again:
            assert s.order is not None
            assert s.order.turn <= held_stamp(before, s.order.run, s.order.taken, s.order.since)
    finally:
        v.close()
