"""The emulator registry and `rotor-bridge emulate MODEL` (run as a real process)."""

from __future__ import annotations

import argparse
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import serial

from bridge.emulators import EMULATORS, create, start
from bridge.emulators.cli import _controller_options, add_arguments, main, run
from bridge.emulators.rotorez import RotorEZ
from tests.support.waiting import slow

REPO = Path(__file__).resolve().parents[2]


def test_registry_knows_every_emulated_model() -> None:
    assert {"rotorez", "rotorcard", "dcu1", "rot2prog", "rot1prog", "md01"} <= set(EMULATORS)
    for name in ("rotorez", "rotorcard", "dcu1"):
        device = create(name)
        assert isinstance(device, RotorEZ) and device.spec.name == name
    for name in ("rot2prog", "rot1prog", "md01"):
        assert create(name).spec.name == name


def test_every_model_has_a_matching_bridge_model() -> None:
    from bridge.protocols import REGISTRY

    assert set(EMULATORS) <= set(REGISTRY)


def test_unknown_model_is_refused_with_the_known_names() -> None:
    with pytest.raises(ValueError, match="rotorcard"):
        start("yaesu-gs232")


def test_start_passes_options_to_the_controller(tmp_path: Path) -> None:
    with start("rotorcard", link=str(tmp_path / "rc"), start_az_deg=12, jitter_deg=0) as port:
        assert port.state().az_deg == 12.0
        assert port.device.brake_delay_s == 0.0


def test_arguments_and_their_defaults() -> None:
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    args = parser.parse_args(["dcu1"])
    assert args.model == "dcu1" and not args.no_power_on_junk
    # unset options stay the model's own defaults; its rotor is as built (a Hy-Gain's stop at
    # south: rotorez.py rule 12)
    assert _controller_options(args) == {"stop_at_south": True}
    args = parser.parse_args(["dcu1", "--speed-deg-s", "3", "--no-power-on-junk", "--baud", "9600"])
    assert _controller_options(args) == {
        "baud": 9600,
        "speed_deg_s": 3.0,
        "power_on_junk": False,
        "stop_at_south": True,
    }
    args = parser.parse_args(["rotorcard"])  # a Yaesu rotor: its stop at north
    assert _controller_options(args) == {"stop_at_south": False}
    args = parser.parse_args(["rot2prog", "--speed-deg-s", "2", "--resolution", "4"])
    assert _controller_options(args) == {"az_speed_deg_s": 2.0, "resolution_ppd": 4}
    with pytest.raises(SystemExit):
        parser.parse_args(["spid-in-2031"])


def test_unusable_link_path_is_an_error_not_a_traceback(capsys: pytest.CaptureFixture[str]) -> None:
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    assert run(parser.parse_args(["rotorez", "--link", "/proc/no/such/dir/rotor"])) == 2
    assert "emulate:" in capsys.readouterr().err


def test_unknown_model_on_the_command_line_exits_2() -> None:
    with pytest.raises(SystemExit) as exc_info:
        main(["yaesu"])
    assert exc_info.value.code == 2


def _read_lines(proc: subprocess.Popen[bytes], count: int, timeout_s: float) -> list[str]:
    """The first `count` stdout lines, read from the raw pipe with a deadline."""
    assert proc.stdout is not None
    fd = proc.stdout.fileno()
    deadline_s = time.monotonic() + slow(timeout_s)
    buffer = b""
    while buffer.count(b"\n") < count:
        remaining_s = deadline_s - time.monotonic()
        ready, _, _ = select.select([fd], [], [], max(0.0, remaining_s))
        assert ready, f"emulator printed only {buffer!r} before the deadline"
        chunk = os.read(fd, 4096)
        assert chunk, f"emulator closed stdout after {buffer!r}"
        buffer += chunk
    return buffer.decode().splitlines()[:count]


def test_emulate_command_serves_until_sigterm(tmp_path: Path) -> None:
    link = tmp_path / "by-id" / "usb-Idiom_Rotor-EZ-if00-port0"
    argv = [
        sys.executable,
        "-m",
        "bridge.emulators",
        "rotorez",
        "--link",
        str(link),
        "--start-az-deg",
        "45",
        "--jitter-deg",
        "0",
        "--firmware",
        "2.1A",
        "--no-power-on-junk",
        "--speed-deg-s",
        "60",
        "--brake-delay-s",
        "0.5",
    ]
    proc = subprocess.Popen(argv, cwd=REPO, stdout=subprocess.PIPE)
    try:
        device_path, link_line = _read_lines(proc, 2, timeout_s=10.0)
        assert device_path.startswith("/dev/pts/")
        assert link_line == str(link)
        assert os.path.realpath(link) == device_path
        with serial.Serial(str(link), 4800, timeout=slow(2)) as client:
            client.write(b"AI1;")
            assert client.read(4) == b";045"
            client.write(b";")
            assert client.read(18) == b"C2000 IDIOM V2.1A "
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=slow(10)) == 0
        assert not os.path.lexists(link)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_emulators_never_import_the_bridge_codec_engine_or_paho() -> None:
    """An emulator built on our own codec would share its misreadings (emulators/__init__.py)."""
    import ast

    forbidden = ("bridge.protocols", "bridge.engine", "bridge.interfaces.mqtt", "paho")
    package = REPO / "bridge" / "emulators"
    offenders = []
    for module in sorted(package.glob("*.py")):
        for node in ast.walk(ast.parse(module.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            offenders += [f"{module.name}: {n}" for n in names if n.startswith(forbidden)]
    assert offenders == []
