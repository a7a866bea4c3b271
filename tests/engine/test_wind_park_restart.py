"""The storm's park across a restart of the bridge (session/wind.py rule 7, runtime/kept.py
rule 4): a park the rotor was seen to reach is kept in the state file beside the storm, and the
next start does not send it again, so a rotor turned by hand at the controller since is not
turned back by itself; a park the bridge died before it was seen reached is finished by the
next start. The state file is the real one (state_store.py, its writer thread), fed each status
the session published, as runtime/rotator.py feeds it."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.core.model import MotionState, RotatorStatus, Target, WindInfo
from bridge.protocols import REGISTRY
from bridge.runtime.composite import merge
from bridge.runtime.kept import Kept
from bridge.runtime.state_store import StateStore
from bridge.session.motion import blind_busy_s
from bridge.session.session import RotatorSession
from tests.engine.test_wind import a_bug_once, wind, windy
from tests.engine.test_wind_park_offline import parked_then_turned_by_hand
from tests.engine.virtual import VirtualRotator

WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180}


def kept(v: VirtualRotator, path: Path) -> Kept:
    """What the state file keeps of the statuses ``v`` published so far (kept.py rule 4)."""
    store = StateStore(path)
    memory = Kept(store, v.cfg.rotator_id, v.cfg.spec, report=lambda *a: None)
    for status in v.published():
        memory.seen_wind(status.wind)
    store.flush()
    return memory


def restart(v: VirtualRotator, path: Path, *, saved: bool = False) -> None:
    """The bridge stops (the port closed) and starts again from the state file (``saved``:
    as the test left it, else what the statuses so far say)."""
    if not saved:
        kept(v, path)
    v.link_down(None)
    v.run_for(1.0)
    again = Kept(StateStore(path), v.cfg.rotator_id, v.cfg.spec, report=lambda *a: None)
    v.session = RotatorSession(
        v.cfg,
        storm=again.storm,
        storm_halted=again.storm_halted,
        storm_arrived=again.storm_arrived,
    )
    v._do(v.session.start(v.now))
    v.link_up()


def refused_in_the_storm(v: VirtualRotator) -> bool:
    """Refused for the storm, said off its park (wind.py rule 10: review 80, these words said
    'parked for the storm' of a rotor 160 degrees off it)."""
    v.command(Target(20.0))
    refusal = v.errors("refused")[-1].message
    return refusal.endswith("(turned off its park after reaching it: the rotor stands at 250°)")


def test_a_park_reached_and_turned_away_by_hand_is_not_sent_again_by_a_restart(
    tmp_path: Path,
) -> None:
    """An MD-01 parked for the storm, turned at its front panel to 250, and the bridge
    restarted in the same storm: the rotor stays where the hand left it (it was turned back to
    the park by itself), and the storm goes on."""
    path = tmp_path / "state.json"
    with windy() as v:
        parked_then_turned_by_hand(v)
        restart(v, path)
        v.run_until(lambda h: h.status.available, 20, "the controller answers again")
        v.run_for(120.0)
        assert v.status.wind is not None and v.status.wind.storm
        assert abs(v.truth().az_deg - 250.0) < 1.0, v.truth()
        assert refused_in_the_storm(v)


def test_a_park_the_bridge_died_in_is_finished_by_the_restart(tmp_path: Path) -> None:
    """The bridge stops two seconds into the storm's park (the controller's turn ends with it):
    the park was never seen reached, so the next start in the storm sends it again, and the
    rotor ends at the park."""
    path = tmp_path / "state.json"
    v = VirtualRotator("gs232b", settings=WIND, emulator={"az_speed_deg_s": 6.0})
    try:
        v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
        wind(v, 90.0)
        v.run_for(2.0)
        v.power_cycle()  # (the turn under way ended: the rotor stands short of the park)
        short = v.truth().az_deg
        assert abs(short - 180.0) > 20.0
        restart(v, path)
        v.run_for(120.0)
        assert v.status.wind is not None and v.status.wind.storm
        assert abs(v.truth().az_deg - 180.0) < 1.0, v.truth()
    finally:
        v.close()


def test_a_dcu1_park_is_sent_again_by_a_restart_whatever_the_file_says(tmp_path: Path) -> None:
    """A DCU-1 cannot say where it stands: its park is never seen reached, not even where a
    state file (hand-edited, or another model's under the same id) says it was."""
    path = tmp_path / "state.json"
    settings = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180}
    v = VirtualRotator("dcu1", settings=settings, emulator={"start_az_deg": 30})
    try:
        cfg = v.cfg.motion
        v.run_for(blind_busy_s(cfg.az_span_deg, cfg) + cfg.brake_delay_s + 1)
        wind(v, 90.0)
        v.run_until(lambda h: h.status.parked, 120, "the park's estimated move over")
        assert kept(v, path).storm_arrived is False
        v.manual_rotate(250.0)
        v.run_for(120.0)
        assert abs(v.truth().az_deg - 250.0) < 1.0
        StateStore(path).set_storm(v.cfg.rotator_id, True, arrived=True)
        restart(v, path, saved=True)
        v.run_for(120.0)
        assert abs(v.truth().az_deg - 180.0) < 1.0, v.truth()
    finally:
        v.close()


def test_a_wind_part_reset_after_the_park_was_reached_does_not_park_again(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Rule 7 through a reset (session.py rule 14): parked, turned by hand, then a bug in the
    wind's part: the reset leaves the rotor where the hand left it."""
    with windy() as v:
        parked_then_turned_by_hand(v)
        raised = a_bug_once(monkeypatch)
        v.run_for(60.0)
        assert raised and v.errors("internal")
        assert abs(v.truth().az_deg - 250.0) < 1.0, v.truth()
        assert v.status.wind is not None and v.status.wind.storm


def test_a_two_box_rotators_park_is_reached_only_when_both_boxes_reached_theirs() -> None:
    """runtime/composite.py rule 3: the rotator's wind is the azimuth box's, but its park is
    kept as reached only when the elevation box's was too (else a restart would leave the
    elevation short of its stow)."""
    there, short = WindInfo(storm=True, arrived=True), WindInfo(storm=True, arrived=False)
    az, el = RotatorStatus("v", wind=there), RotatorStatus("v", wind=short)
    merged = merge("v", az, el).wind
    assert merged is not None and merged.storm and not merged.arrived
    both = merge("v", az, RotatorStatus("v", wind=there)).wind
    assert both is not None and both.arrived


def test_the_reached_park_is_kept_with_the_storm_and_goes_with_it(tmp_path: Path) -> None:
    """state_store.py: ``storm_arrived`` beside ``storm``; the storm's end clears it, and only
    a true in the file says it (a damaged value parks again)."""
    path = tmp_path / "state.json"
    s = StateStore(path)
    assert s.set_storm("tower", True, arrived=True)
    again = StateStore(path)
    assert again.storm("tower") and again.storm_arrived("tower")
    assert not again.storm_halted("tower")
    assert s.set_storm("tower", False, arrived=True)  # (no storm: nothing reached)
    assert not StateStore(path).storm_arrived("tower")
    path.write_text('{"rotators": {"tower": {"storm": true, "storm_arrived": "yes"}}}')
    assert not StateStore(path).storm_arrived("tower")
    kept = Kept(StateStore(path), "tower", REGISTRY["md01"], report=lambda *a: None)
    assert kept.storm and not kept.storm_arrived
