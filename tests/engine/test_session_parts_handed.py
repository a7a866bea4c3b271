"""The session runs the parts it is handed (session/parts.py rule 4, session/session.py rule
17), in virtual time: a feature's part declared in its package alone turns the rotor, with
state of its own; handed parts run in their order, are woken when they ask, and one that raises
is reset by its own Part and named, while the stops and targets go on."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import cast

import pytest

import bridge.feature
from bridge.app import worker_config
from bridge.core.model import MotionState, Source, Target
from bridge.feature import Feature, session_parts
from bridge.features import FEATURES
from bridge.session import motion as mo
from bridge.session.parts import Part, Proposal, Scene, Wake
from bridge.session.session import RotatorSession
from bridge.settings import RotatorSettings
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
SETTINGS = RotatorSettings(id="v", model="rotorez", port="/dev/ttyVIRTUAL")


class Beacon:
    """A toy feature's own state, one per session: it turns the rotor to 123 once, after 3 s."""

    def __init__(self, s: RotatorSession) -> None:
        self.aim = s.cfg.aim
        self.sent = False


def _beacon_step(s: RotatorSession, scene: Scene) -> Proposal | None:
    beacon = cast(Beacon, s.own["beacon"])
    if beacon.sent or scene.now < 3.0 or not mo.at_rest(scene.motion):
        return None
    beacon.sent = True
    target = Target(123.0, None, Source.MQTT)
    return Proposal(target=beacon.aim.judge(target, scene.motion.position_deg))


BEACON = Part[RotatorSession](
    "beacon", Wake.STEP, True, lambda s: True, _beacon_step, lambda s, now: None, state=Beacon
)


def test_a_features_part_turns_the_rotor_from_its_declaration_alone(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Registered with its part, a feature is run by every session, the app's (worker_config
    hands the registry's parts) and one made without parts handed in; its state is its own."""
    toy = Feature("beacon", "docs/architecture.md", "turns to 123 once", part=BEACON)
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, toy))
    assert isinstance(
        RotatorSession(replace(worker_config(SETTINGS), parts=None)).own["beacon"], Beacon
    )
    v = rig("rotorez")
    assert v.cfg.parts is not None and v.cfg.parts[-1] is BEACON
    v.run_until(lambda h: h.status.target_az_deg == 123.0, 10, "the beacon's target")
    v.run_until_state(MotionState.IDLE, 60)
    assert v.status.bearing_deg == pytest.approx(123.0, abs=v.cfg.deadband_deg)
    assert v.status.last_command_source == Source.MQTT.value


def recording(
    name: str, log: list[tuple[str, float]], *, deciding: bool = True
) -> Part[RotatorSession]:
    def step(s: RotatorSession, scene: Scene) -> None:
        log.append((name, scene.now))

    return Part(name, Wake.STEP, deciding, lambda s: True, step, lambda s, now: None)


def test_handed_parts_run_in_their_order_the_deciding_ones_before_the_measuring(rig: Rig) -> None:
    log: list[tuple[str, float]] = []
    parts = (recording("b", log), recording("m", log, deciding=False), recording("a", log))
    v = rig("rotorez", cfg=replace(worker_config(SETTINGS), parts=parts))
    v.run_until(lambda h: h.status.available, 10, "the first reading")
    log.clear()
    v.run_for(3)
    order = "".join(name for name, _ in log)
    assert order and order.replace("bam", "") == ""  # each step: b, a (as handed), then m


def test_a_handed_part_is_woken_when_it_asks(rig: Rig) -> None:
    log: list[tuple[str, float]] = []
    due = replace(recording("due", log), wakeup=lambda s, now: 7.25 if now < 7.25 else None)
    v = rig("rotorez", cfg=replace(worker_config(SETTINGS), parts=(due,)))
    v.run_for(10)
    assert 7.25 in [t for _, t in log]  # a step at the time it asked for, none of the polls'


def test_a_handed_part_that_raises_is_reset_by_its_part_and_named_and_targets_go_on(
    rig: Rig,
) -> None:
    resets: list[float] = []
    steps: list[float] = []

    def step(s: RotatorSession, scene: Scene) -> None:
        steps.append(scene.now)
        if len(steps) == 3:
            raise RuntimeError("boom")

    flaky = Part[RotatorSession](
        "flaky", Wake.STEP, True, lambda s: True, step, lambda s, now: resets.append(now)
    )
    v = rig("rotorez", cfg=replace(worker_config(SETTINGS), parts=(flaky,)))
    v.run_until(lambda h: len(resets) == 1, 10, "the reset")
    assert [e.message for e in v.errors("internal")] == [
        "flaky failed (a bug, see the log): flaky reset"
    ]
    v.target(200)
    v.run_until(lambda h: h.status.target_az_deg == 200.0, 10, "the target taken")
    v.run_until_state(MotionState.IDLE, 60)
    assert v.status.bearing_deg == pytest.approx(200.0, abs=v.cfg.deadband_deg)
    assert len(steps) > 3  # it runs on after its reset


def test_the_app_hands_the_registered_features_parts_in_the_steps_order() -> None:
    """bridge/feature.py rule 2: tracking and following before the wind (whose storm ends
    them), the wind before auto-park (which waits while it parks); health measures after the
    poll."""
    parts = session_parts()
    assert [p.name for p in parts if p.deciding] == ["tracking", "following", "wind", "auto-park"]
    assert [p.name for p in parts if not p.deciding] == ["health"]
    assert len({p.name for p in parts}) == len(parts)  # each reset and named as its own
    assert worker_config(SETTINGS).parts == parts


def test_a_parts_status_that_keeps_raising_is_reported_once_per_kind_and_the_status_goes_out(
    rig: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    """session/parts.py rule 6: its status is asked at every status the session builds, several
    a second while the rotor turns. One that raises at each is a bug said once per kind of
    failure (as a listener's, runtime/listeners.py), on R/error and in the log, and the rest of
    the status still goes out (the rotor's bearing, the other parts' blocks)."""
    asked: list[float] = []
    kinds = [KeyError("label"), KeyError("label"), ValueError("aimed")]

    def status(s: RotatorSession) -> object:
        asked.append(s.status.bearing_deg or 0.0)
        raise kinds[min(len(asked), len(kinds)) - 1 if len(asked) < 40 else 0]

    resets: list[float] = []
    shows = Part[RotatorSession](
        "shows",
        Wake.STEP,
        False,
        lambda s: False,
        lambda s, scene: None,
        lambda s, now: resets.append(now),
        status=status,
    )
    fine = Part[RotatorSession](
        "fine",
        Wake.STEP,
        False,
        lambda s: False,
        lambda s, scene: None,
        lambda s, now: None,
        status=lambda s: {"ok": True},
    )
    v = rig("rotorez", cfg=replace(worker_config(SETTINGS), parts=(shows, fine)))
    v.run_until(lambda h: h.status.available, 10, "the first reading")
    t = v.now
    v.target(200)
    v.run_until_state(MotionState.IDLE, 60)
    assert len(asked) > 40  # asked at every status while it turned
    assert [e.message for e in v.errors("internal")] == [
        "shows failed (a bug, see the log): shows reset",  # KeyError
        "shows failed (a bug, see the log): shows reset",  # ValueError, once too
    ]
    assert len([r for r in caplog.records if r.exc_info is not None]) == 2
    assert len(resets) == 2
    moving = [s for s in v.published(since=t) if s.state is MotionState.MOVING]
    assert moving and all(s.features == {"fine": {"ok": True}} for s in moving)
    assert v.status.bearing_deg == pytest.approx(200.0, abs=v.cfg.deadband_deg)
