from __future__ import annotations

import subprocess
import sys

from bridge import __version__


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "bridge", *args], capture_output=True, text=True, timeout=30
    )


def test_ports_lists_serial_ports_or_says_there_are_none() -> None:
    out = cli("ports")
    assert out.returncode == 0, out.stderr
    assert "use this path:" in out.stdout or "no serial ports found" in out.stdout


def test_version_and_help() -> None:
    assert cli("--version").stdout.strip() == f"rotor-bridge {__version__}"
    helptext = cli("--help").stdout
    for sub in ("run", "check-config", "ports", "emulate", "demo"):
        assert sub in helptext


def test_run_without_a_configuration_says_how_to_give_one() -> None:
    out = cli("run")
    assert out.returncode == 2 and "--config" in out.stderr
