"""Review 96: the storm's park the bridge finishes after a restart in the storm (session/wind.py
rule 7: a park the bridge died in before it was seen reached is sent again by the next start)
is the same storm's park, yet it takes a new place in the order of commands (mailbox.py rule
10b keeps one turn's place only within a run: a storm kept across a restart counts as none, and
the new run's mailbox names nothing yet), past every place the first run showed, though no
command was put between.

What a remote sees (interfaces/mqtt/remote.py rule 10): an operator pressed STOP against the
park (stamped with the place R/status showed, the park's), the station lost its link and its
bridge restarted (a power blip does both); the new run's R/status shows the park turning at a
place past the stamp, read as a newer turn, and the held STOP is dropped: the rotor turns on
though the operator stopped it. The same shape as review 91, by a restart instead of an
offline. In virtual time, with the real state file (state_store.py, its writer thread) fed
every status as runtime/rotator.py feeds it, and a run's places as runtime/rotator.py starts
them (``places_after`` the file's ``since``, the session's ``order`` from it)."""

from __future__ import annotations

from pathlib import Path

from bridge.core.model import MotionState, RotatorStatus
from bridge.interfaces.mqtt.remote import held_stamp
from bridge.runtime.kept import Kept
from bridge.runtime.state_store import StateStore
from bridge.session.mailbox import Mailbox
from bridge.session.session import RotatorSession
from tests.engine.test_wind_park_offline import WIND, storm
from tests.engine.virtual import VirtualRotator


def kept(v: VirtualRotator, path: Path) -> Kept:
    """The state file as the statuses ``v`` published so far left it (kept.py rules 4, 12)."""
    store, clock = StateStore(path), [0.0]
    memory = Kept(
        store, v.cfg.rotator_id, v.cfg.spec, report=lambda *a: None, clock=lambda: clock[0]
    )
    for t, status in v.statuses:
        clock[0] = t  # (rule 12's ORDER_SAVE_S in the statuses' own time)
        memory.seen_wind(status.wind)
        memory.seen_order(status.order)
    store.flush()
    return memory


def restart(v: VirtualRotator, path: Path) -> int:
    """The bridge dies mid-park (the controller's turn ends with it) and starts again from the
    state file: a new mailbox counting on after the places the file reserved, a new session
    given the storm and the places kept (runtime/rotator.py). Returns where the new run's
    statuses begin."""
    kept(v, path)
    v.power_cycle()
    v.link_down(None)
    v.run_for(1.0)
    again = Kept(StateStore(path), v.cfg.rotator_id, v.cfg.spec, report=lambda *a: None)
    v.mailbox.close()
    v.mailbox = Mailbox()
    v.mailbox.places_after(again.since)
    v.session = RotatorSession(
        v.cfg,
        storm=again.storm,
        storm_halted=again.storm_halted,
        storm_arrived=again.storm_arrived,
        storm_place=again.storm_place,  # (the place its park took: kept.py rule 4)
        order=(again.since, again.turn_place, again.lock_place),
        place=v.mailbox.own_place,
    )
    begun = len(v.statuses)
    v._do(v.session.start(v.now))
    v.link_up()
    return begun


def turns(statuses: list[RotatorStatus]) -> set[int]:
    return {s.order.turn for s in statuses if s.order is not None and s.order.turn}


def test_a_storm_park_finished_by_a_restart_keeps_the_place_it_had(tmp_path: Path) -> None:
    """A GS-232B at rest at 10 / 30; a storm; two seconds into the park the bridge dies and
    starts again in the storm. The park goes again and reaches 180 / 0 (as it should); every
    status of the new run names the park at the place the first run showed for it."""
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
        assert len(first) == 1, first  # (the park's one place in the first run)
        # a remote's STOP pressed now, held over the partition: stamped from the places the
        # statuses showed before it (remote.py rule 10's ledger of runs and places)
        before: dict[str, tuple[int, ...]] = {}
        for s in v.published():
            if s.order is not None:
                before[s.order.run] = (*before.get(s.order.run, ()), s.order.taken)
        restarted = restart(v, path)
        v.run_until(
            lambda h: abs(h.truth().az_deg - 180.0) < 1.0 and abs(h.truth().el_deg) < 1.0,
            180,
            "at its park, sent again by the restart",
        )
        assert v.status.wind is not None and v.status.wind.storm
        again = [s for s in v.published()[restarted:] if s.order is not None and s.order.turn]
        assert turns(again) == first
        # (so the held STOP still stands at each: no status shows a turn past its stamp)
        for s in again:
            assert s.order is not None
            assert s.order.turn <= held_stamp(before, s.order.run, s.order.taken, s.order.since)
    finally:
        v.close()


def test_a_storm_park_never_sent_before_a_restart_takes_a_new_place(tmp_path: Path) -> None:
    """The kept place is the park's own, never the turn shown before the storm: a GS-232B at
    rest at 10 / 30 falls silent; a storm begins (its park waits for the controller); the
    bridge restarts in the storm and the controller answers: the park goes, at a place of the
    new run, past a remote's STOP pressed before the storm (stamped against the 10 / 30 turn,
    the turn the state file kept), which so never stops it (review 83)."""
    path = tmp_path / "state.json"
    v = VirtualRotator("gs232b", settings=WIND, emulator={"az_speed_deg_s": 6.0}, own_places=True)
    try:
        v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
        v.target(10.0, 30.0)
        v.run_until(lambda h: abs(h.truth().az_deg - 10) < 1, 120, "at 10")
        before: dict[str, tuple[int, ...]] = {}  # a remote's STOP pressed before the storm
        for s in v.published():
            if s.order is not None:
                before[s.order.run] = (*before.get(s.order.run, ()), s.order.taken)
        v.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "offline")
        storm(v)
        assert v.status.wind is not None and v.status.wind.waiting  # (no park sent)
        restarted = restart(v, path)
        v.set_silent(False)
        v.run_until(
            lambda h: abs(h.truth().az_deg - 180.0) < 1.0 and abs(h.truth().el_deg) < 1.0,
            180,
            "at its park, sent by the new run",
        )
        again = [s for s in v.published()[restarted:] if s.target_az_deg is not None]
        assert again
        for s in again:
            assert s.order is not None
            assert s.order.turn > s.order.since  # (a place of the new run's)
            assert s.order.turn > held_stamp(before, s.order.run, s.order.taken, s.order.since)
    finally:
        v.close()
