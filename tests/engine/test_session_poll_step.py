"""session.py rule 20 in virtual time: a tick with nothing due but the poll runs the poll alone,
and that poll step hands out what the whole step would have, at the same wake-up, leaving the
session as the whole step would have left it (checked at every poll step of many scenarios,
against the whole step run on a copy made just before). And it is the poll step that writes a
turning rotor's polls: one whole step per reading, not two.
"""

from __future__ import annotations

import copy
import enum
import logging
import re
from collections import deque
from collections.abc import Callable
from dataclasses import replace
from functools import partial
from types import BuiltinFunctionType, FunctionType, MethodType
from typing import Any

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from bridge.app import worker_config
from bridge.core.model import MotionState
from bridge.emulators.rotorez_models import Outcome
from bridge.feature import session_parts
from bridge.session.parts import Part, Scene, Wake
from bridge.session.session import Action, RotatorSession
from bridge.settings import RotatorSettings
from tests.engine.test_session_quiet_hold import count_steps
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
_SKIP = {"tick", "_step", "_poll_until"}  # the tests' wrappers; rule 20's mark (reset by the poll)


def _snap(obj: object, seen: dict[int, int]) -> object:
    """Everything ``obj`` holds, as plain comparable values (objects by their fields)."""
    if isinstance(obj, float):
        return repr(obj)  # (nan and -0.0 as they are)
    if obj is None or isinstance(obj, bool | int | str | bytes):
        return obj
    if isinstance(obj, enum.Enum):
        return repr(obj)
    if isinstance(obj, bytearray | memoryview):
        return bytes(obj)
    if isinstance(obj, type | FunctionType | BuiltinFunctionType | MethodType | partial):
        return ("callable", getattr(obj, "__qualname__", repr(type(obj))))
    if isinstance(obj, logging.Logger | re.Pattern):
        return repr(obj)
    if id(obj) in seen:
        return ("seen", seen[id(obj)])
    seen[id(obj)] = len(seen)
    if isinstance(obj, list | tuple | deque):
        return (type(obj).__name__, [_snap(x, seen) for x in obj])
    if isinstance(obj, dict):
        items = [(repr(_snap(k, seen)), _snap(v, seen)) for k, v in obj.items()]
        return ("dict", sorted(items, key=lambda kv: kv[0]))
    if isinstance(obj, set | frozenset):
        return ("set", sorted(repr(_snap(x, seen)) for x in obj))
    fields: dict[str, object] = dict(getattr(obj, "__dict__", {}))
    for cls in type(obj).__mro__:
        slots = getattr(cls, "__slots__", ())
        for name in (slots,) if isinstance(slots, str) else slots:
            if name not in fields and hasattr(obj, name):
                fields[name] = getattr(obj, name)
    if not fields:
        return ("opaque", type(obj).__qualname__, repr(obj))
    return (
        type(obj).__qualname__,
        {k: _snap(v, seen) for k, v in sorted(fields.items()) if k not in _SKIP},
    )


def snapshot(session: RotatorSession) -> object:
    return _snap(session, {})


def check_poll_steps(v: VirtualRotator) -> list[float]:
    """From now on, every tick that rule 20 hands to the poll step is checked against the whole
    step run on a copy of the session made just before it: the same actions, the same
    wake-up, the same session after. The times of the poll steps are returned."""
    session, hits = v.session, []
    tick = session.tick

    def checked(now: float) -> list[Action]:
        if not now < session._poll_until:
            return tick(now)
        twin = copy.deepcopy(session)
        expected = RotatorSession._step(twin, now)  # the whole step, as before rule 20
        got = tick(now)
        assert got == expected, (now, got, expected)
        assert session.next_wakeup() == twin.next_wakeup(), now
        assert snapshot(session) == snapshot(twin), now
        hits.append(now)
        return got

    session.tick = checked  # type: ignore[method-assign]
    return hits


# -- what a scenario does: each event, then some time ---------------------------------------------
def _target(v: VirtualRotator, az: float) -> None:
    v.target(az)


def _turn(v: VirtualRotator, az: float) -> None:
    v.manual_rotate(az)


_EVENTS: dict[str, Callable[[VirtualRotator, float], None]] = {
    "target": _target,
    "turn": _turn,  # from the front panel: moving, polled fast, no command
    "stop": lambda v, _az: v.stop(),
    "lock": lambda v, _az: v.lock(True),
    "unlock": lambda v, _az: v.lock(False),
    "silent": lambda v, _az: v.set_silent(True),  # silence's timeout: not answering
    "heard": lambda v, _az: v.set_silent(False),
    "unplug": lambda v, _az: v.link_down(),
    "plug": lambda v, _az: None if v.connected else v.link_up(),
    "power": lambda v, _az: v.power_cycle(),  # options owed again (a power-on byte)
}

_MODELS: list[tuple[str, dict[str, Any], dict[str, Any], dict[str, Any] | None]] = [
    # model, settings, emulator, options
    ("rotorez", {}, {"speed_deg_s": 4.0}, None),
    ("rotorez", {"park_az_deg": 0, "park_after_idle_s": 5}, {}, {"unstick": True}),  # auto-park on
    ("rotorcard", {}, {}, None),
    ("rot2prog", {}, {"start_az_deg": 100}, None),
    ("gs232b", {}, {}, {"speed": "2"}),
    ("easycomm2", {}, {}, None),
    ("rt21", {}, {}, None),
    ("rc2800", {}, {}, None),
    ("prosistel", {}, {}, None),
    ("satel", {}, {}, None),  # silent while it slews
    ("dcu1", {}, {}, None),  # never answers: never a poll step
]

_SCENARIO = st.lists(
    st.tuples(
        st.sampled_from(sorted(_EVENTS)),
        st.sampled_from([10.0, 90.0, 180.0, 270.0, 350.0]),
        st.sampled_from([0.05, 0.3, 1.0, 4.0, 12.0, 65.0]),  # (65: past an options refresh)
    ),
    min_size=1,
    max_size=6,
)


def run_checked(model: int, scenario: list[tuple[str, float, float]]) -> list[float]:
    """``scenario`` on ``_MODELS[model]``, every poll step checked; their times."""
    name, settings_, emulator, options = _MODELS[model]
    v = VirtualRotator(name, settings=settings_, emulator=emulator, options=options)
    try:
        hits = check_poll_steps(v)
        v.run_for(3.0)
        for what, az, wait_s in scenario:
            _EVENTS[what](v, az)
            v.run_for(wait_s)
        v.set_silent(False)
        v.run_for(5.0)
    finally:
        v.close()
    if name == "dcu1":
        assert not hits
    return hits


@pytest.mark.parametrize("model", range(len(_MODELS)), ids=[m[0] for m in _MODELS])
@settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(scenario=_SCENARIO)
def test_the_poll_step_does_what_the_whole_step_would(
    model: int, scenario: list[tuple[str, float, float]]
) -> None:
    hits = run_checked(model, scenario)
    event(f"{_MODELS[model][0]}: {'no' if not hits else 'some' if len(hits) < 20 else 'many'}")


@pytest.mark.parametrize("model", [0, 3, 4], ids=["rotorez", "rot2prog", "gs232b"])
@pytest.mark.parametrize(
    "scenario",
    [
        # a stop merged right after one: its repeat owed 0.1 s later (stops.py rule 1)
        [("turn", 350.0, 1.0), ("stop", 0.0, 0.05), ("stop", 0.0, 0.05), ("stop", 0.0, 3.0)],
        [("target", 350.0, 2.0), ("stop", 0.0, 0.03), ("stop", 0.0, 0.3), ("stop", 0.0, 2.0)],
        # a target waiting for the brake window after a stop, then another during the turn
        [("target", 180.0, 1.5), ("stop", 0.0, 0.3), ("target", 90.0, 4.0), ("target", 10.0, 9)],
        # silence's timeout while turning, and back
        [("turn", 10.0, 0.5), ("silent", 0.0, 4.0), ("heard", 0.0, 2.0), ("target", 90.0, 5)],
        # a power-on byte: options owed again
        [("power", 0.0, 1.0), ("target", 90.0, 65.0), ("turn", 200.0, 3.0)],
    ],
    ids=["stop repeat while turned by hand", "stop repeat", "target waits", "silence", "power"],
)
def test_the_poll_step_does_what_the_whole_step_would_in_these(
    model: int, scenario: list[tuple[str, float, float]]
) -> None:
    assert run_checked(model, scenario)


def test_a_turning_rotor_ez_writes_its_polls_in_poll_steps_and_takes_each_reading_in_a_whole_step(
    rig: Rig,
) -> None:
    """Turned from its front panel, polled every 0.2 s: each poll is written by a poll step
    (rule 20), each reading taken by a whole step; every poll step checked against the whole
    step; the status follows the rotor as before."""
    v = rig("rotorez", emulator={"speed_deg_s": 4.0})
    v.run_until_state(MotionState.IDLE, 30)
    v.manual_rotate(350.0)
    v.run_until_state(MotionState.MOVING, 10)
    v.run_for(1)
    t0 = v.now
    hits = check_poll_steps(v)
    whole = count_steps(v)
    v.run_for(10)
    polls = [w.t for w in v.writes if w.data == b"AI1;" and w.t >= t0]
    assert len(polls) >= 45
    assert sorted(hits) == polls  # every poll by a poll step, and no other poll step
    assert len(whole) <= len(polls) + 1  # the reading's (a poll written just before the end)
    assert v.status.bearing_deg == pytest.approx(v.truth().az_deg, abs=2)


def test_no_poll_step_while_a_part_that_reads_the_time_is_on(rig: Rig) -> None:
    """Auto-park counts its quiet spell at every step (Wake.STEP): every tick is a whole step,
    and it parks after its spell as before."""
    v = rig("rotorez", settings={"park_az_deg": 0, "park_after_idle_s": 5})
    hits = check_poll_steps(v)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(90)
    # (at rest at 90: its idle state may be shown only with the park's target, or not at all
    # where the park goes out in the step the brake ends, as the polls fall)
    rest = (MotionState.BRAKING, MotionState.IDLE)
    v.run_until(lambda h: h.state in rest and h.truth().az_deg > 85, 60, "at 90")
    v.run_until(lambda h: h.truth().az_deg < 5 and not h.truth().is_moving, 60, "parked")
    assert not hits


class Meter:
    """A toy measuring part's state: the readings it saw; every third one it raises."""

    def __init__(self, s: RotatorSession) -> None:
        self.seen = 0


def _meter_step(s: RotatorSession, scene: Scene) -> None:
    meter = s.own["meter"]
    assert isinstance(meter, Meter)
    meter.seen += 1
    if meter.seen % 3 == 0:
        raise RuntimeError("a bug")


METER = Part[RotatorSession](
    "meter", Wake.MOTION, False, lambda s: True, _meter_step, lambda s, now: None, state=Meter
)


def test_a_measuring_part_reset_after_a_bug_is_run_again_by_the_next_step(rig: Rig) -> None:
    """A part woken by the motion that raised is reset and has seen no motion (session.py rule
    14): the next tick is a whole step that runs it, not a poll step."""
    settings_ = RotatorSettings(id="v", model="rotorez", port="/dev/ttyVIRTUAL")
    cfg = replace(worker_config(settings_), parts=(*session_parts(), METER))
    v = rig("rotorez", cfg=cfg, emulator={"speed_deg_s": 4.0})
    v.run_until_state(MotionState.IDLE, 30)
    hits = check_poll_steps(v)
    v.manual_rotate(350.0)
    v.run_for(10)
    assert hits
    assert len(v.errors("internal")) >= 10


def test_a_new_series_of_lost_stops_is_counted_from_one_after_a_target_went_out(rig: Rig) -> None:
    """stops.py rule 2: ``check_stop`` starts its count of stops again once none is out (a
    target went out); a poll step skips it, so none runs while a count is left to start again.
    An RT-21 (it takes a new target while turning) that never gets a stop: three stops, the
    error; a new target goes out at once; a STOP in the next poll exchange, lost too, has its
    own error after its own three (before: the count went on from 3 and none came)."""
    v = rig("rt21")
    checked = check_poll_steps(v)
    v.run_until_state(MotionState.IDLE, 30)
    stop = v.session.controller.link.codec.encode_stop()
    v.target(300.0)
    v.run_for(3.0)
    for frame in stop if isinstance(stop, list) else [stop]:
        v.drop_writes(frame, 50)  # a runaway: no stop reaches the controller
    v.stop()
    v.run_for(7.0)
    assert len(v.errors("stop")) == 1
    v.target(100.0)
    polls = len(v.frames(Outcome.QUERY))
    v.run_until(lambda h: len(h.frames(Outcome.QUERY)) > polls, 2.0, "the next poll")
    v.stop()  # in that poll's exchange
    t = v.now
    v.run_for(9.0)
    assert [e.message for e in v.errors("stop", since=t)] == [
        "rotor still turning after 3 stop commands; stop it at the controller"
    ]
    assert checked  # poll steps ran, each as the whole step would have


@pytest.mark.parametrize(
    ("model", "option"),
    [
        ("rotorez", ("unstick", True)),
        ("gs232b", ("speed", "2")),
        ("rt21", None),
        ("rot2prog", None),
        ("rc2800", None),
        ("satel", None),
    ],
)
def test_the_poll_step_does_what_the_whole_step_would_through_faults_and_refreshes(
    rig: Rig, model: str, option: tuple[str, Any] | None
) -> None:
    """What the generated scenarios leave out, each poll step against the whole step on a copy:
    an option set at rest and two refreshes of it (options.py rule 1), a controller deaf for
    2 s while turning, a jammed rotor (its stall), garbled polls, the brake lever."""
    v = rig(model)
    checked = check_poll_steps(v)
    v.run_until_state(MotionState.IDLE, 30)
    if option is not None:
        v.option(*option)
    v.run_for(130.0)
    v.target(200.0)
    v.run_for(1.5)
    v.set_deaf(True)
    v.run_for(2.0)
    v.set_deaf(False)
    v.run_for(5.0)
    v.jam()
    v.run_for(20.0)
    v.unjam()
    v.target(100.0)
    v.run_for(1.0)
    asked = copy.deepcopy(v.session.controller.link.codec).encode_query()  # (the live one's
    v.garble_writes(asked[0] if isinstance(asked, list) else asked, b"zz", 2)  # state kept)
    v.run_for(30.0)
    v.press_brake()
    v.run_for(5.0)
    assert checked
