from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import pytest

from bridge import __version__
from bridge.cli import build_parser, main
from tests.support import ROOT, bridge_env, run_cli, slow


def test_ports_lists_serial_ports_or_says_there_are_none() -> None:
    out = run_cli("ports")
    assert out.returncode == 0, out.stderr
    assert "use this path:" in out.stdout or "no serial ports found" in out.stdout


def test_version_and_help() -> None:
    assert run_cli("--version").stdout.strip() == f"rotor-bridge {__version__}"
    helptext = run_cli("--help").stdout
    for sub in ("run", "check-config", "ports", "emulate", "demo"):
        assert sub in helptext


def test_run_without_a_configuration_says_how_to_give_one() -> None:
    out = run_cli("run")
    assert out.returncode == 2 and "--config" in out.stderr


def test_run_loads_neither_the_emulators_nor_the_demo_and_demo_still_has_its_options() -> None:
    """What a start of ``run`` imports is start-up CPU (benchmarks/exchange_cpu.py): not the
    emulators, the demo, check-config's report, or the DX cluster's code without ``[dxcluster]``."""
    code = (
        "import sys\n"
        "from bridge.cli import build_parser\n"
        "args = build_parser(sys.argv[1:]).parse_args(sys.argv[1:])\n"
        "import bridge.app\n"
        "lazy = ('bridge.emulators', 'bridge.demo', 'bridge.interfaces.dxcluster',"
        " 'bridge.settings.report')\n"
        "print(sorted(m for m in sys.modules if m.startswith(lazy)))"
    )
    run = subprocess.run(
        [sys.executable, "-c", code, "--log-level", "INFO", "run", "-c", "bridge.toml"],
        capture_output=True,
        text=True,
        check=True,
        env=bridge_env(),
    )
    assert run.stdout.strip() == "[]"
    assert "--models" in run_cli("demo", "--help").stdout
    assert "--link" in run_cli("emulate", "--help").stdout


#: the front ends a rotator asks for with its own keys, and their code
FRONT_ENDS = (
    "bridge.interfaces.gs232",
    "bridge.interfaces.loggers",
    "bridge.interfaces.ptylines",
    "bridge.interfaces.rotctld",
    "bridge.interfaces.tcplines",
    "bridge.interfaces.web",
    "bridge.interfaces.wsjtx",
)


def built_app(tmp_path: Path, sections: str, rotator: str) -> list[str]:
    """The bridge built (not started) from a configuration in a fresh interpreter: what it then
    says of its front ends, and the front ends' modules it imported."""
    code = f"""
import sys
from bridge.app import App
from bridge.settings import settings_from
tmp = {str(tmp_path)!r}
rotator = {{"id": "a", "model": "rotorez", "port": tmp + "/tty", {rotator}}}
settings = settings_from({{
    "state_file": tmp + "/state.json", "mqtt": {{"host": "127.0.0.1", "port": 1}},
    {sections} "rotators": [rotator]}}, {{}})
app = App(settings)
print(len(app.rotctld), len(app.emulations), bool(app.loggers), app.wsjtx is not None)
print(sorted({{m.rsplit(".", 1)[0] if m.count(".") > 2 else m
    for m in sys.modules if m.startswith({FRONT_ENDS!r})}}))
"""
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=bridge_env()
    )
    return run.stdout.splitlines()


def test_a_rotator_brings_in_only_the_front_ends_it_asks_for(tmp_path: Path) -> None:
    """Each front end's code (rotctld, GS-232/Easycomm/DCU-1, the loggers' UDP ports, WSJT-X,
    the console) is a part of the CPU a start takes (benchmarks/exchange_cpu.py): a rotator with
    none of their keys imports none of them; one with all of them gets each."""
    assert built_app(tmp_path, "", "") == ["0 0 False False", "[]"]
    asked = (
        '"rotctld_port": 45001, "gs232_port": 45002, "dcu1_pty": tmp + "/dcu1", '
        '"pst_udp_port": 45003'
    )
    said, modules = built_app(tmp_path, '"wsjtx": {"enabled": True},', asked)
    assert said == "1 2 True True"
    assert modules == str(sorted(set(FRONT_ENDS) - {"bridge.interfaces.web"}))


def subcommands() -> dict[str, argparse.ArgumentParser]:
    actions = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    assert len(actions) == 1
    return dict(actions[0].choices)


def test_every_subcommand_is_listed_in_the_main_help() -> None:
    helptext = run_cli("--help").stdout
    assert set(subcommands()) == {"run", "check-config", "ports", "emulate", "demo", "remote"}
    for name in subcommands():
        assert name in helptext


@pytest.mark.parametrize("name", sorted(subcommands()))
def test_every_subcommand_help_says_what_it_does(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    description = subcommands()[name].description
    assert description and len(description.split()) >= 8, description  # a sentence, not a word
    with pytest.raises(SystemExit) as exc:
        main([name, "--help"])
    assert exc.value.code == 0
    shown = " ".join(capsys.readouterr().out.split())  # argparse re-wraps the text
    assert " ".join(description.split()) in shown


def test_every_option_of_every_command_says_what_it_does() -> None:
    """`rotor-bridge demo --help` listed --mqtt-host and --mqtt-port bare: a user must not
    have to read the code to learn what an option is for."""
    bare = []
    parsers = [("rotor-bridge", build_parser()), *subcommands().items()]
    for name, parser in parsers:
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                continue
            if not action.help or len(action.help.split()) < 3:
                bare.append(f"{name} {'/'.join(action.option_strings) or action.dest}")
    assert bare == []


@pytest.mark.parametrize("args", [("check-config", "-c", "config/example.toml"), ("ports",)])
def test_a_reader_that_left_early_ends_a_printing_command_without_a_traceback(
    args: tuple[str, ...],
) -> None:
    # `rotor-bridge check-config -c FILE | head -3`: the pipe is closed before it prints
    read, write = os.pipe()
    os.close(read)
    try:
        out = subprocess.run(
            [sys.executable, "-m", "bridge", *args],
            stdout=write,
            stderr=subprocess.PIPE,
            text=True,
            env=bridge_env(),
            cwd=str(ROOT),
            timeout=slow(30),
        )
    finally:
        os.close(write)
    assert out.returncode == 1, out
    assert out.stderr == "", out.stderr


def test_check_config_without_a_file_says_to_name_one_not_that_rotators_are_missing() -> None:
    out = run_cli("check-config")
    assert out.returncode == 2, out
    assert out.stderr == (
        "rotor-bridge: no configuration file given: pass --config FILE (see config/example.toml) "
        "or set ROTOR_BRIDGE_CONFIG\n"
    ), out.stderr
