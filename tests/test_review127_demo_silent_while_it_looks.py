"""Review 127: since the demo's look at its MQTT port waits for a CONNACK (cf33222e, and
1dc74693 made that wait CONNACK_TIMEOUT_S, 10 s, plus LOOK_AGAIN_S), a port that takes
connections and never answers (a hung broker, an SSH tunnel whose far end is gone: rule 6's own
case) keeps the demo silent for 11 s: ``./demo`` prints nothing at all, no "looking for a
broker at ...", until its verdict. The README promises a demo that "says clearly what it does";
a user facing a blank terminal that long takes it for hung and presses Ctrl-C, which the demo
then ignores until the wait is over (test_review127_demo_ctrl_c_during_broker_look.py). The same
silence covers a broker that is only slow to let a client in (measured: 13 s before the banner
for a broker 3 s to CONNACK, 32 s for one 6 s to CONNACK).

A real demo run; on its port a program that takes connections and never answers."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

from bridge import demo
from bridge.cli import build_parser


def test_the_demo_says_where_it_looks_for_a_broker_before_it_waits_for_one(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    with socket.create_server(("127.0.0.1", 0)) as silent:  # takes connections, answers none
        port = silent.getsockname()[1]
        args = build_parser().parse_args(
            ["demo", "--mqtt-port", str(port), "--web-port", "0", "--no-private-broker"]
        )
        code = demo.run(args)
    said = capsys.readouterr()
    lines = (said.out + said.err).splitlines()
    verdict = next(
        (i for i, line in enumerate(lines) if "answers no MQTT" in line), None
    )  # said once the whole wait is over
    assert code == 1 and verdict is not None, said.err
    before = [line for line in lines[:verdict] if f"127.0.0.1:{port}" in line]
    assert before, (
        f"nothing was said while the demo waited for a CONNACK; its first words: {lines[:3]}"
    )
