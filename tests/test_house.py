"""The house style docs/architecture.md asks of every module in bridge/, kept by a test: an
opening docstring that says what the module owns. Size is guidance, not a test: a module is cut
where its job divides, never to come under a count (a 600-line module with one job beats two
with half a job each). And of the tests: no deadline written as a bare number, so that every one
scales with the machine's load (tests/support/waiting.py)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODULES = sorted((ROOT / "bridge").rglob("*.py"))
# a number where a deadline goes: a timeout, a wait, a join, a socket's patience, a monotonic end
BARE_DEADLINE = re.compile(
    r"\btimeout=\d|\.wait\((timeout=)?\d|\.join\((timeout=)?\d|settimeout\(\d|monotonic\(\) \+ \d"
)


def test_modules_are_found() -> None:
    assert len(MODULES) > 50


def test_every_module_opens_with_what_it_owns() -> None:
    bare = [
        str(p.relative_to(ROOT))
        for p in MODULES
        if p.read_text().strip() and not ast.get_docstring(ast.parse(p.read_text()))
    ]
    assert not bare, f"modules without an opening docstring: {bare}"


def test_no_deadline_in_the_tests_is_a_bare_number() -> None:
    """A deadline is ``slow(seconds)`` or a helper's ``timeout_s`` (which the helper scales),
    so ROTOR_TEST_SLOWDOWN reaches all of them; a number that is no deadline (a quiet period, a
    poll) says so on its line."""
    bare = [
        f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
        for path in sorted((ROOT / "tests").rglob("*.py"))
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if BARE_DEADLINE.search(line) and "not a deadline" not in line
    ]
    assert not bare, "deadlines not scaled by slow():\n" + "\n".join(bare)
