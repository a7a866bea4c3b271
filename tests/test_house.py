"""The house style docs/architecture.md asks of every module in bridge/, kept by a test: an
opening docstring that says what the module owns, and a size that still reads as one thing."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODULES = sorted((ROOT / "bridge").rglob("*.py"))
MAX_LINES = 420  # "a module past ~400 lines is asking to be split along a seam it already has"


def test_modules_are_found() -> None:
    assert len(MODULES) > 50


def test_every_module_opens_with_what_it_owns() -> None:
    bare = [
        str(p.relative_to(ROOT))
        for p in MODULES
        if p.read_text().strip() and not ast.get_docstring(ast.parse(p.read_text()))
    ]
    assert not bare, f"modules without an opening docstring: {bare}"


def test_no_module_grows_past_the_size_of_one_thing() -> None:
    big = {
        str(p.relative_to(ROOT)): n
        for p in MODULES
        if (n := len(p.read_text().splitlines())) > MAX_LINES
    }
    assert not big, f"modules over {MAX_LINES} lines, split along a seam they have: {big}"
