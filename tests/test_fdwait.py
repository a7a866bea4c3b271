"""interfaces/fdwait.py: waits on descriptors however high their numbers (select() refused
every one from 1024 on, and the thread that waited ended), and no wait in bridge/ calls
select() any more."""

from __future__ import annotations

import os
import resource
from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.interfaces.fdwait import readable, writable

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def high_pipe() -> Iterator[tuple[int, int]]:
    """A pipe whose ends are numbered above 1023."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard < 1200:
        pytest.skip(f"this machine's hard limit on open files ({hard}) is below 1,200")
    if soft < 1200:
        resource.setrlimit(resource.RLIMIT_NOFILE, (min(hard, 2048), hard))
    r, w = os.pipe()
    high_r, high_w = os.dup2(r, 1100), os.dup2(w, 1101)
    os.close(r)
    os.close(w)
    try:
        yield high_r, high_w
    finally:
        os.close(high_r)
        os.close(high_w)
        resource.setrlimit(resource.RLIMIT_NOFILE, (soft, hard))


def test_a_descriptor_above_1023_is_waited_on(high_pipe: tuple[int, int]) -> None:
    r, w = high_pipe
    assert readable((r,), 0) == []  # nothing yet, no wait
    assert writable(w, 0)
    os.write(w, b"x")
    assert readable((r, -1), 0) == [r]  # a closed one (-1) is passed over


def test_a_hang_up_counts_as_ready_as_select_had_it() -> None:
    r, w = os.pipe()
    try:
        os.close(w)
        assert readable((r,), None) == [r]  # the read that follows says b"": the end
        assert os.read(r, 1) == b""
    finally:
        os.close(r)


def test_no_wait_in_bridge_calls_select() -> None:
    """fdwait.py rule 1; core/polling.py's poller for a system without poll() (Windows, the
    remote: its select() has no such limit) is the one exception."""
    found = [
        f"{path.relative_to(ROOT)}:{n}"
        for path in sorted((ROOT / "bridge").rglob("*.py"))
        if path != ROOT / "bridge" / "core" / "polling.py"
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if "select.select(" in line and not line.lstrip().startswith("#")
    ]
    assert not found, f"select() refuses descriptors from 1024 on: {found}"
