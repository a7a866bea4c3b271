"""Review 144, finding 4: since e7d107fa a STOP (and a lock ON) typed while the demo's console
has lost the broker is kept by paho for the next connection, and the console prints nothing:
its parent e7d107fa^ said "not sent (R/stop STOP): the console has lost the broker" (rule 3b
still says so of a bearing). The user who typed ``s`` at a turning rotor reads silence as done,
while the STOP waits for a reconnect 1 to 5 s away at best, and never goes if the broker does
not come back: the rotor runs on to its target, and nobody was told to stop it another way (a
lock ON alike: someone climbs the tower of a rotator that is not locked yet).
Fixed: such a last word is said held for the next connection (console.py rule 6).

Real nats-server (MQTT 3.1.1); the console's connection through review 139's relay, cut."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.topics import Topics
from tests.support.brokers import Nats, find_nats
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath


@pytest.fixture
def nats(tmp_path: Path) -> Iterator[Nats]:
    if find_nats() is None:
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    n = Nats(tmp_path / "nats").start()
    yield n
    n.stop()


@pytest.mark.parametrize(("typed", "word"), [("s", "STOP"), ("lock on", "ON")])
def test_a_stop_typed_while_the_console_is_cut_off_says_it_has_not_gone_yet(
    nats: Nats, capsys: pytest.CaptureFixture[str], typed: str, word: str
) -> None:
    relay = DeadPath(nats.port)
    topics = Topics(BASE, {"rotorez": BASE})
    console = console_through(relay.port, topics, mqtt5=False)
    try:
        assert console.sync(slow(20)), "the MQTT 3.1.1 console never connected through the relay"
        tries = len(relay.levels)
        relay.cut()
        wait_until(lambda: len(relay.levels) > tries, 20, "the console trying to reconnect")
        capsys.readouterr()
        assert console.command(typed)  # typed now: the rotor is turning, or someone climbs
        said = capsys.readouterr().out
    finally:
        console.close()
        relay.close()
    assert word in said and "lost the broker" in said, (
        f"the console said nothing of the {typed!r} it could not send yet: {said!r}"
    )
