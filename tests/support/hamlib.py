"""Hamlib's rotctl as the independent judge of an emulator (tests/emulators/test_*_hamlib.py):
what a run printed, what the emulator logged, and ``rotor-bridge emulate MODEL`` driven by one
rotctl run. The ``rotctl_run`` fixture (tests/emulators/conftest.py) runs rotctl on a port."""

from __future__ import annotations

import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bridge.emulators.pty import EmulatedPort
from tests.support import ROOT
from tests.support.waiting import slow

#: a rotctl run: (..., port, ..., *commands) -> what it printed (the fixtures say what comes first)
Rotctl = Callable[..., subprocess.CompletedProcess[str]]


def rotctl_argv(rotctl_path: str, hamlib_model: int, path: str, baud: int) -> list[str]:
    """One rotctl run, bounded in time: ``-m hamlib_model -r path -s baud``."""
    argv = ["timeout", f"{slow(20):g}", rotctl_path, "-m", str(hamlib_model), "-r", path]
    return [*argv, "-s", str(baud)]


def run(argv: list[str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(argv, capture_output=True, text=True, timeout=slow(25), check=False)


def values(result: subprocess.CompletedProcess[str]) -> list[str]:
    """What rotctl printed, word by word; it must have succeeded."""
    assert result.returncode == 0, f"rotctl failed: {result.stdout!r} {result.stderr[-800:]!r}"
    return result.stdout.split()


def commands(port: EmulatedPort[Any]) -> list[tuple[bytes, str]]:
    """Every command the emulator took, with its outcome."""
    return [(f.data, f.outcome) for f in port.log()]


def emulate_and_drive(
    tmp_path: Path,
    rotctl_path: str,
    model: str,
    options: list[str],
    judge: tuple[int, int],
    *commands: str,
) -> subprocess.CompletedProcess[str]:
    """``rotor-bridge emulate MODEL --link PATH options`` (here ``python -m bridge.emulators``)
    driven by one run of rotctl ``-m judge[0] -s judge[1] commands``: it prints its pty and its
    link, one a line, and SIGTERM ends it with status 0. The rotctl run is returned."""
    link = tmp_path / model
    argv = [sys.executable, "-m", "bridge.emulators", model, "--link", str(link), *options]
    proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().startswith("/dev/pts/")
        assert proc.stdout.readline().strip() == str(link)
        done = run([*rotctl_argv(rotctl_path, judge[0], str(link), judge[1]), *commands])
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=slow(10)) == 0
        return done
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
