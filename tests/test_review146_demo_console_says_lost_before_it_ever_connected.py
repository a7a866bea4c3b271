"""Review 146, finding 6: since 9b73f8b9 the demo's console (bridge/demo/console.py rule 6)
refuses a command typed while it is not connected with "the console has lost the broker",
before its first connection too: the demo reads the terminal even when its console's first
sync gave up (5 s, a slow or refusing broker), and a user whose console never reached the broker
reads that it lost it (a broker that was there and went: wait for it), not that it was never
reached (the address, the login, the broker's limits). Its parent 1998b9a5 said nothing and sent
the command on the first connection.

Real mosquitto; the console's connection through review 139's relay, refusing from the start.

Fixed: console.py rule 6."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath


def test_a_command_typed_before_the_first_connection_does_not_say_the_broker_was_lost(
    broker: Mosquitto, capsys: pytest.CaptureFixture[str]
) -> None:
    relay = DeadPath(broker.port)
    relay.close_all = True  # the broker refuses the console from the start
    topics = Topics(BASE, {"rotorez": BASE})
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        wait_until(lambda: len(relay.levels) > 0, 20, "the console trying to connect")
        capsys.readouterr()
        assert console.command("200")
        said = capsys.readouterr().out
    finally:
        console.close()
        relay.close()
    assert "not sent" in said, said
    assert "lost the broker" not in said, f"a broker never reached is said lost: {said!r}"
