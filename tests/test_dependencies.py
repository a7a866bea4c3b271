"""The declared floors of the runtime dependencies are the versions scripts/test-lowest runs the
suite at: tests/lowest-constraints.txt pins each to the floor in pyproject.toml, so a floor
raised in one place and not the other (or a dependency added without one) fails here."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def floors() -> dict[str, str]:
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    out = {}
    for spec in declared:
        found = re.fullmatch(r"([A-Za-z0-9_.-]+)\s*>=\s*([0-9][0-9.]*)(,.*)?", spec)
        assert found, f"{spec!r}: every runtime dependency needs a floor (>=)"
        out[found[1].lower()] = found[2]
    return out


def pins() -> dict[str, str]:
    lines = (ROOT / "tests" / "lowest-constraints.txt").read_text().splitlines()
    out = {}
    for line in lines:
        if line.strip() and not line.startswith("#"):
            name, version = line.split("==")
            out[name.strip().lower()] = version.strip()
    return out


def version(text: str) -> tuple[int, ...]:
    """2.2 and 2.2.0 are one version."""
    parts = [int(p) for p in text.split(".")]
    while parts and parts[-1] == 0:
        parts.pop()
    return tuple(parts)


def test_the_lowest_constraints_are_the_declared_floors() -> None:
    declared, pinned = floors(), pins()
    assert sorted(declared) == sorted(pinned)
    assert [n for n in declared if version(declared[n]) != version(pinned[n])] == []
