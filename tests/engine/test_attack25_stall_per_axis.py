"""Attack 25's High finding, its other sides: on an az/el rotor each axis off its target is
judged stalled on its own (motion.py rule 3), and nothing else is.

- A healthy move whose one axis arrives early, or creeps slower than the moving polls' noise
  band while the other turns, is no stall: an axis at its target is not judged, and an axis's
  progress is its own movement from where it last moved (not rule 1's shared anchor, which the
  other axis moves at every poll).
- A box that turns its axes one after the other (``ModelSpec.axes_in_turn``; none of the
  families here does, their fact sheets and emulators turn both at once) shows its waiting
  axis still while the other turns: that axis is not called stalled, either axis's movement is
  both axes' progress there.
- The stall of a jammed elevation is counted by rotor health at its elevation, not at the
  azimuth (``stall_elevations``), and its error names it.
"""

from __future__ import annotations

from dataclasses import replace

from bridge.core.model import ErrorKind, MotionState
from bridge.features.health.payload import health_doc
from bridge.protocols import REGISTRY
from bridge.session import motion as mo
from bridge.session.config import HealthConfig
from bridge.session.health_judge import Judge, Move
from tests.engine.virtual import VirtualRotator, settled_at

STALL_S = 10.0  # the bridge's default stall_timeout_s
POLL_MARGIN_S = 2.0  # a moving poll or two for the reading that tells it (not a deadline)


def test_an_elevation_that_arrives_early_is_no_stall_while_the_azimuth_turns_on() -> None:
    """190 degrees of azimuth at 6 degrees a second (32 s) and 5 of elevation (at its target in
    about a second): the elevation stands at its target for 30 s, three stall timeouts, and is
    not judged; the azimuth arrives."""
    v = VirtualRotator("gs232b", emulator={"start_az_deg": 0, "start_el_deg": 0})
    assert v.cfg.motion.stall_timeout_s == STALL_S
    v.run_until_state(MotionState.IDLE, 30)
    t0 = v.now
    v.target(190, 5)
    v.run_until(settled_at(190, 5), 60, "the azimuth's arrival")
    v.run_until_state(MotionState.IDLE, 30)
    assert v.errors(since=t0) == []
    assert not [f for f in v.frames(since=t0) if f.data == b"S"], "a healthy move was stopped"
    health = v.status.health
    assert health is not None and health.stalls == 0


def test_an_elevation_creeping_below_the_noise_band_per_poll_is_no_stall() -> None:
    """An elevation at 0.6 degrees a second (set so: ``el_speed_deg_s``) moves 1.2 degrees a
    moving poll, inside the 2 degree noise band from where the azimuth's movement puts the
    shared anchor at every poll: judged by its own movement since it last moved, it
    progresses every other poll and climbs its 10 degrees while the azimuth turns."""
    v = VirtualRotator(
        "gs232b",
        settings={"el_speed_deg_s": 0.6},
        emulator={"start_az_deg": 0, "start_el_deg": 0, "el_speed_deg_s": 0.6},
    )
    v.run_until_state(MotionState.IDLE, 30)
    t0 = v.now
    v.target(190, 10)
    v.run_until(settled_at(190, 10), 60, "the arrival")
    v.run_until_state(MotionState.IDLE, 30)
    assert v.errors(ErrorKind.STALLED, since=t0) == []
    assert v.truth().el_deg == 10.0


def test_a_jammed_elevation_is_counted_by_rotor_health_at_its_elevation() -> None:
    """Rotor health's stall is where the rotor is held: elevation 0, not azimuth (the attack:
    counted at azimuth 190, where nothing holds it)."""
    v = VirtualRotator("gs232b", emulator={"start_az_deg": 10, "start_el_deg": 0})
    v.run_until_state(MotionState.IDLE, 30)
    v.device._el.jam(v.now)  # type: ignore[attr-defined]  # ice on the elevation
    t0 = v.now
    v.target(190, 45)
    v.run_until(lambda r: r.state is MotionState.STALLED or r.now - t0 > 60, 90, "a stall")
    said = [r.message for r in v.errors(ErrorKind.STALLED, since=t0)]
    assert len(said) == 1 and said[0].startswith("rotor stalled at elevation 0°"), said
    assert "its elevation made no progress" in said[0], said
    health = v.status.health
    assert health is not None
    assert health.stalls == 1
    assert health.stall_azimuths_deg == ()
    assert health.stall_elevations_deg == (0.0,)


def _readings(cfg: mo.MotionConfig) -> tuple[mo.Motion, list[mo.Event]]:
    """A box that turns the azimuth first, 10 to 190 at 6 degrees a second (30 s) with its
    elevation waiting at 0, then the elevation to 45 (5 s): readings every second."""
    m = mo.link_up(mo.Motion(), cfg, 0.0)
    m, _ = mo.reading(m, cfg, 10.0, 0.0, 0.0)
    m, _ = mo.tick(m, cfg, 10.0)
    assert mo.at_rest(m)
    m = mo.commanded(m, cfg, 190.0, 10.0, 45.0)
    events: list[mo.Event] = []
    t, az, el = 10.0, 10.0, 0.0
    while m.state is mo.MOVING and t < 60.0:
        t += 1.0
        if az < 190.0:
            az = min(190.0, az + 6.0)
        elif el < 45.0:
            el = min(45.0, el + 9.0)
        m, ev = mo.reading(m, cfg, az, t, el)
        events += ev
    return m, events


def test_a_box_that_turns_its_axes_in_turn_has_its_waiting_axis_called_stalled_by_nobody() -> None:
    """Motion rule 3's ``axes_in_turn``: the elevation waits still for 30 s while the azimuth
    turns, then turns itself and arrives; judged per axis, as a box turning both at once is, it
    would be stopped 10 s into the azimuth's turn."""
    spec = REGISTRY["gs232b"]
    in_turn = mo.MotionConfig(replace(spec, axes_in_turn=True), stall_timeout_s=STALL_S)
    m, events = _readings(in_turn)
    assert mo.Event.STALLED not in events, events
    assert mo.Event.ARRIVED in events and (m.position_deg, m.el_position_deg) == (190.0, 45.0)
    together = mo.MotionConfig(spec, stall_timeout_s=STALL_S)  # (the same readings, judged
    m, events = _readings(together)  # per axis: the waiting elevation is a jammed one)
    assert mo.Event.STALLED in events and m.stalled == "elevation", events


def test_elevation_stalls_repeating_warn_at_their_elevation_and_are_kept() -> None:
    """health_judge.py rule 3: three elevation stalls near 0 warn "near elevation 0°" (not at
    the azimuths the rotor stood at, 10, 190, 300: scattered, no warning), and the state
    file's memory keeps them; one written before they were kept still reads."""
    judge = Judge(HealthConfig(), True, wraps=True)
    for el in (0.0, 1.0, 0.0):
        judge.add(Move(stalled_at_deg=el, stalled_axis="el"))
    report = judge.report()
    assert report.stalls == 3 and report.stall_azimuths_deg == ()
    assert report.stall_elevations_deg == (0.0, 1.0, 0.0)
    assert [w for w in report.warnings if "stalls near" in w] == [
        "3 stalls near elevation 0° (within 5°) among the last 3: something holds the rotor there"
    ]
    assert health_doc(report)["stall_elevations"] == [0.0, 1.0, 0.0]
    kept = Judge(HealthConfig(), True, report.memory, wraps=True).report()
    assert kept.stall_elevations_deg == (0.0, 1.0, 0.0)
    older = {k: v for k, v in report.memory.items() if k != "stall_el_at"}
    assert Judge(HealthConfig(), True, older, wraps=True).report().stalls == 3
