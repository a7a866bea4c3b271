"""The control lease's end by itself is in the audit trail (runtime/operators.py rule 2): the
holder named as its operator, ``lease`` as its interface; a release or a renewal before the end
writes no such line. Virtual time, as tests/engine/test_operators.py."""

from __future__ import annotations

from pathlib import Path

from bridge.core.model import AuditEvent, Origin, Source
from bridge.runtime.operators import Operators
from bridge.runtime.state_store import StateStore
from bridge.session.mailbox import Mailbox
from tests.engine.test_operators import HOLDER, T0, Clock, Timers


def operators(tmp_path: Path) -> tuple[Operators, Clock, Timers, list[AuditEvent]]:
    clock, timers, audit = Clock(), Timers(), []
    ops = Operators(
        "t",
        StateStore(tmp_path / "state.json"),
        Mailbox(),
        wall=clock,
        bearing=lambda: 123.0,
        report=lambda *a: None,
        on_audit=audit.append,
        timer=timers,
    )
    return ops, clock, timers, audit


def test_the_lease_ending_by_itself_is_an_audit_line_naming_the_holder(tmp_path: Path) -> None:
    ops, clock, timers, audit = operators(tmp_path)
    ops.claim("DL1ABC", 2, HOLDER)
    [(_, fire)] = timers.live()
    clock.now += 120
    fire()
    assert ops.holder is None
    ended = audit[-1].as_dict()
    assert ended == {
        "time": T0 + 120,
        "rotator": "t",
        "operator": "DL1ABC",
        "interface": "lease",
        "peer": None,
        "command": "control expired",
        "result": "executed",
        "bearing_before": 123.0,
    }
    fire()  # a second firing (a late timer) finds nothing more to end: no second line
    assert [e.command for e in audit] == ["control expired"]  # (the claim's: the judge's)


def test_a_lease_released_or_fired_early_writes_no_expiry(tmp_path: Path) -> None:
    ops, clock, timers, audit = operators(tmp_path)
    ops.claim("DL1ABC", 2, HOLDER)
    [(_, fire)] = timers.live()
    clock.now += 60
    fire()  # early (the clock was set back): it re-arms, nothing ended
    ops.release(Origin(Source.MQTT, "G4XYZ"))
    clock.now += 120
    for _, late in timers.live():
        late()
    assert audit == []  # the claim's and the release's lines are the judge's (rotator.py)
