"""Review 152 (cold review of 415730e0): on review 150's dead path (the path under the bridge's
connections dies without a word, the broker up throughout), the stop lane is back within
STOP_DEAD_PATH_S and puts the main connection's path in doubt (connection.py rule 6,
``prove_path``): the main connection pings within STOP_KEEPALIVE_S and, unanswered, is made
again. What the log tells the operator then is the main connection's own end, a ping unanswered
for 2 s; but paho reports that end twice (``_check_keepalive`` closes the socket and says so,
then ``loop_misc`` sees the same unanswered ping and says so again, the connection no longer
up), and the second report is read as a connection attempt the broker never answered: an ERROR
that the broker "did not answer the connection within the keep-alive (30 s): it took the
connection and then said nothing ... check that the broker runs and answers", about a
connection it had accepted long before, 2 s after the ping, the broker healthy throughout.

The path dies at the test's own proxy (tests/support/mqtt_proxy.py ``blackhole``).

Fixed: each attempt's end is judged once (connection.py rule 6, paho_client.py
``attempts``); shown here on the main connection's own keep-alive (5 s), as 415730e0 was taken
back."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from tests.faults.behind_a_proxy import lanes_behind
from tests.support.mqtt_proxy import MqttProxy
from tests.support.waiting import slow, wait_until

KEEPALIVE_S = 5  # the main connection's (mqtt.keepalive_s at its least)


def test_the_main_connection_made_again_on_a_dead_path_is_not_said_as_a_broker_that_never_answered(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    # a dashboard on the broker's own port; the main connection's end comes soon
    with lanes_behind(tmp_path, MqttProxy, keepalive_s=KEEPALIVE_S) as b:
        proxy, app = b.proxy, b.app
        caplog.clear()
        caplog.set_level(logging.INFO, logger="bridge")
        proxy.blackhole()  # the path under every connection dies without a word
        wait_until(
            lambda: not app.client.connected.is_set(),
            slow(2 * KEEPALIVE_S + 4),
            "the main connection given up",
        )
        wait_until(app.client.connected.is_set, slow(15), "the main connection back")
        said = [
            r.getMessage()
            for r in caplog.records
            if r.levelno >= logging.ERROR and "did not answer the connection" in r.getMessage()
        ]
        assert not said, (
            f"the main connection, accepted long before and given up for a ping unanswered "
            f"2 s on a dead path, was told to the operator as a broker that never answered "
            f"a connection: {said}"
        )
