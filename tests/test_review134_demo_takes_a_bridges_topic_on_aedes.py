"""Review 134, finding 4: bridge/demo/__init__.py rule 4 refuses a ``--base-topic`` that a bridge
uses (``<base>/bridge/state`` retained), reading it through the demo's console after one
``sync``; 343a5337 made that console work on MQTT 3.1.1 brokers (review 127), and its test
(nats, two retained topics) passes. On aedes 0.46 (Node-RED's node-red-contrib-aedes, in the
project's broker matrix), which "hands a subscription's retained messages beside the messages
published after it, not before them" (docs/brokers.md), the sync marker comes back ahead of
much of what a real bridge holds retained: with a bridge's usual few dozen state topics and
its Home Assistant configs there, ``<base>/bridge/state`` has not come yet when the check
reads it, and the demo runs its bridge on the real bridge's base topic (its banner saying "a
real bridge's are not touched"): it takes over the real bridge's topics and Home Assistant
node ids, and at its end leaves ``<base>/bridge/state`` retained "offline" while the real
bridge runs. (The parent's console was refused on aedes and read nothing: the same, said no
better.)

Real aedes 0.46; a real bridge's retained state stands in as an MQTT 3.1.1 client publishes
it; read back the same way, until aedes falls quiet."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge import demo
from bridge.cli import build_parser
from tests.support.brokers import Aedes, find_aedes
from tests.test_review127_demo_takes_a_bridges_topic_on_mqtt311 import publish_retained
from tests.test_review134_demo_on_aedes_leaves_retained import retained_on


@pytest.fixture
def aedes(tmp_path: Path) -> Iterator[Aedes]:
    if find_aedes() is None:
        pytest.fail("aedes is not installed (scripts/bootstrap: npm ci in tests/brokers/aedes)")
    a = Aedes(tmp_path / "aedes").start()
    yield a
    a.stop()


def test_a_demo_on_aedes_refuses_a_base_topic_a_bridge_uses(
    aedes: Aedes,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    # a real bridge with eight rotators: their state topics, its own, its Home Assistant configs
    held = {f"shack/rot{i}/{leaf}": b"x" for i in range(8) for leaf in range(14)}
    held |= {f"homeassistant/sensor/rotorbridge_shack/e{j}/config": b"{}" for j in range(150)}
    real = {"shack/bridge/state": b"online", "shack/lock/state": b"ON"}
    publish_retained(aedes.port, held | real)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(work))
    args = build_parser().parse_args(
        ["demo", "--mqtt-port", str(aedes.port), "--web-port", "0", "--no-private-broker"]
        + ["--base-topic", "shack", "--duration-s", "2"]
    )
    code = demo.run(args)
    said = capsys.readouterr()
    after = retained_on(aedes.port, "shack/#")
    assert {t: after.get(t) for t in real} == real, (
        f"the demo (exit {code}) changed the real bridge's retained state: "
        f"{ {t: after.get(t) for t in real} }; it said: {said.out[:200]}"
    )
    assert code == 2 and "belongs to a bridge" in said.err, said.err
