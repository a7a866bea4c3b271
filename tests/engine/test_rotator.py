"""The rotator's judgement of commands: the one place for limits, lock and capabilities.
No port is opened: every refusal here happens before anything could reach a worker."""

from __future__ import annotations

import pytest

from bridge.app import worker_config
from bridge.engine.rotator import Rotator
from bridge.engine.state_store import StateStore
from bridge.errors import Refused
from bridge.model import ErrorEvent, SetOption, Stop, Target
from bridge.settings import RotatorSettings


def rotator(model: str = "rotorez", **settings: object) -> tuple[Rotator, list]:
    events: list[ErrorEvent] = []
    cfg = worker_config(RotatorSettings(id="t", model=model, port="/dev/null", **settings))
    return Rotator(cfg, StateStore(None), lambda s: None, events.append), events


def code(rot: Rotator, command) -> str:  # noqa: ANN001
    with pytest.raises(Refused) as exc:
        rot.submit(command)
    return exc.value.code


def test_limits_are_judged_on_what_the_controller_will_get() -> None:
    rot, events = rotator(az_max_deg=350.6)
    assert code(rot, Target(350.6)) == "limits"  # a Rotor-EZ would be sent 351
    assert "becomes 351" in events[-1].message
    assert code(rot, Target(350.4)) == "offline"  # within limits; refused only for the link
    assert code(rot, Target(float("nan"))) == "limits"
    assert code(rot, Target(-0.1)) == "limits"


def test_lock_refuses_motion_but_never_a_stop() -> None:
    rot, events = rotator()
    rot.set_lock(True)
    assert code(rot, Target(10)) == "locked"
    rot.submit(Stop())  # accepted: queued for the worker
    assert events[-1].kind == "refused" and "locked" in events[-1].message


def test_capabilities() -> None:
    rot, _ = rotator("rotorcard")
    assert code(rot, SetOption("jam", True)) == "unsupported"
    assert code(rot, Target(10, 20)) == "unsupported"  # no elevation axis
    assert code(rot, Target(None, None)) == "invalid"
    spid, _ = rotator("rot2prog", el_max_deg=90)
    assert code(spid, Target(10, 91)) == "limits"
    assert code(spid, Target(10.3, 89.9)) == "offline"  # SPID rounds down: no rounding past
