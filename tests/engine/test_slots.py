"""The session's three big objects keep every attribute in a slot (docs/performance.md, 'Reads
Python 3.11 never specialised'): with more than 30 attributes in an instance dictionary, Python
3.11 never specialises a method call on it. An attribute a later change adds without its slot
still works (``__dict__`` is kept, so that a test can wrap one instance's method) but brings
the slow calls back: these tests say which one."""

from __future__ import annotations

import ast
import inspect

import pytest

from bridge.session.controller import Controller
from bridge.session.link import Link
from bridge.session.session import RotatorSession
from tests.engine.virtual import VirtualRotator

SLOTTED = (RotatorSession, Controller, Link)


def _assigned(cls: type) -> set[str]:
    """Every ``self.NAME`` the class's own code assigns."""
    names = set()
    for node in ast.walk(ast.parse(inspect.getsource(cls))):
        targets: list[ast.expr] = []
        if isinstance(node, ast.Assign):
            targets = list(node.targets)
        elif isinstance(node, ast.AnnAssign | ast.AugAssign):
            targets = [node.target]
        for target in targets:
            for sub in ast.walk(target):
                if (
                    isinstance(sub, ast.Attribute)
                    and isinstance(sub.value, ast.Name)
                    and sub.value.id == "self"
                ):
                    names.add(sub.attr)
    return names


@pytest.mark.parametrize("cls", SLOTTED, ids=lambda c: c.__name__)
def test_every_attribute_its_code_sets_has_its_slot(cls: type) -> None:
    missing = _assigned(cls) - set(cls.__slots__)
    assert not missing, f"{cls.__name__}: add {sorted(missing)} to __slots__"


@pytest.mark.parametrize("model", ["rotorez", "gs232b", "md01", "satel", "rot2prog", "dcu1"])
def test_a_session_that_ran_keeps_nothing_outside_its_slots(model: str) -> None:
    """Attributes set from elsewhere are found by running: a turn, a stop, a lost and found
    line, a lock (a dictionary left empty is what the slots promise)."""
    with VirtualRotator(model) as v:
        v.run_for(3.0)
        v.target(90.0)
        v.run_for(2.0)
        v.stop()
        v.run_for(2.0)
        v.link_down()
        v.run_for(1.0)
        v.link_up()
        v.lock(True)
        v.run_for(3.0)
        session = v.session
        link = session.controller.link
        assert link is not None
        for obj in (session, session.controller, link):
            assert vars(obj) == {}, f"{type(obj).__name__}: {sorted(vars(obj))} not in slots"
