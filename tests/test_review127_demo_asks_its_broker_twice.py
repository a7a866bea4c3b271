"""Review 127: the demo's look at its broker (bridge/demo/__init__.py ``_run``) sends its CONNECT
and waits for the CONNACK twice: ``answers(host, port)`` and then, for rule 8's login check,
``connack(host, port)`` again, which throws the first answer's code away and asks anew. Each
waits for the broker's CONNACK, up to CONNACK_TIMEOUT_S (review 122 gave a slow broker that
long). Against a broker slow to let a client in (an authentication plugin asking a server, a
loaded Raspberry Pi: review 122's case) the demo sits silent for two of the broker's waits before
its own console and bridge even begin theirs (measured: a broker 3 s to CONNACK, the banner 13 s
after the start; one 6 s to CONNACK, 32 s), 6 and 12 s of it this second CONNECT's. The broker's
log shows two anonymous clients (``auto-...``, keep-alive 10) for every demo started.

Real mosquitto, whose log (``-v``) names each client it lets in."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from bridge import demo
from bridge.cli import build_parser
from tests.support.mosquitto import Mosquitto

PROBE = re.compile(r"New client connected from \S+ as auto-\S+ \(p\d, c1, k10\)")


def test_the_demo_asks_its_broker_for_one_connack_before_it_starts(
    broker: Mosquitto,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(work))
    args = build_parser().parse_args(
        ["demo", "--mqtt-port", str(broker.port), "--web-port", "0", "--no-private-broker"]
        + ["--duration-s", "1"]
    )
    code = demo.run(args)
    said = capsys.readouterr()
    assert code == 0, said.err
    assert f"the MQTT broker already running at 127.0.0.1:{broker.port}" in said.out, said.out
    probes = PROBE.findall(broker.log.read_text())
    assert len(probes) == 1, f"the demo's CONNECTs before it started: {probes}"
