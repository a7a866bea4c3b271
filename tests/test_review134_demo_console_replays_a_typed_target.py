"""Review 134, finding 1: since 343a5337 the demo's console connects in MQTT 3.1.1 on a broker
that speaks nothing newer (nats-server), and a typed line reaches the bridge there. A line typed
while the console's connection is down (the broker restarting, a network blip: the console says
nothing of it) is not refused: paho keeps the QoS 1 PUBLISH and sends it when it next connects,
seconds later (reconnect_delay 1..5 s), with nothing in MQTT 3.1.1 to mark it old. A bearing
typed into a console that showed nothing turns the rotor whenever the broker comes back
(architecture.md principle 7: no stale or replayed command moves a rotor; the remote's
commands are "never queued for a later connection", interfaces/mqtt/remote.py). The parent
did the same on MQTT 5 brokers (no message expiry either); on nats its console never connected.
Fixed: a move typed while the console has lost the broker is refused and said (console.py rule
6), never sent.

Real nats-server; the console's own connection runs through a relay that is cut and restored
(the bridge's would not be); what reaches the broker is read by an MQTT 3.1.1 client there."""

from __future__ import annotations

import contextlib
import socket
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge.demo.console import Console
from bridge.demo.screen import Screen
from bridge.interfaces.mqtt.topics import Topics
from tests.support.brokers import Nats, NoMqtt5, find_nats
from tests.support.waiting import slow, wait_until

BASE = "rotor-demo-r134"


@pytest.fixture
def nats(tmp_path: Path) -> Iterator[Nats]:
    if find_nats() is None:
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    n = Nats(tmp_path / "nats").start()
    yield n
    n.stop()


class Cuttable(NoMqtt5):
    """A relay that passes MQTT 3.1.1 through, and can drop what it carries and refuse new
    connections for a while (a network blip on the console's path alone)."""

    def cut(self) -> None:
        self.close_all = True
        with self._lock:
            socks, self._socks = self._socks, []
        for s in socks:  # (shut down first: a close alone under another thread's blocked
            with contextlib.suppress(OSError):  # read sends no FIN: review 139 (5), flaky)
                s.shutdown(socket.SHUT_RDWR)
            with contextlib.suppress(OSError):
                s.close()

    def restore(self) -> None:
        self.close_all = False


class Watcher:
    """An MQTT 3.1.1 client on the broker itself: every message under the demo's base topic,
    in the order it got them."""

    def __init__(self, port: int) -> None:
        self.got: list[tuple[str, str]] = []
        self._cond = threading.Condition()
        ready = threading.Event()
        c = paho.Client(CallbackAPIVersion.VERSION2, client_id="r134w", protocol=paho.MQTTv311)
        c.on_connect = lambda client, *_: client.subscribe(f"{BASE}/#", 1)
        c.on_subscribe = lambda *_: ready.set()
        c.on_message = self._on_message
        c.connect("127.0.0.1", port)
        c.loop_start()
        self._client = c
        assert ready.wait(slow(20)), "the watcher never subscribed"

    def _on_message(self, client: paho.Client, u: Any, msg: paho.MQTTMessage) -> None:
        with self._cond:
            self.got.append((msg.topic, msg.payload.decode()))
            self._cond.notify_all()

    def wait_for(self, topic: str, payload: str) -> list[tuple[str, str]]:
        """Everything that came up to (topic, payload), which must come."""
        with self._cond:
            assert self._cond.wait_for(lambda: (topic, payload) in self.got, slow(20)), self.got
            return self.got[: self.got.index((topic, payload))]

    def close(self) -> None:
        self._client.disconnect()
        self._client.loop_stop()


def test_a_bearing_typed_while_the_console_is_cut_off_is_not_sent_when_it_reconnects(
    nats: Nats,
) -> None:
    relay = Cuttable(nats.port)
    watcher = Watcher(nats.port)
    topics = Topics(BASE, {"rotorez": BASE})
    console = console_through(relay.port, topics, mqtt5=False)
    try:
        assert console.sync(slow(20)), "the MQTT 3.1.1 console never connected through the relay"
        tries = len(relay.levels)
        relay.cut()
        # the console has seen its connection go: it has tried again, and been closed
        wait_until(lambda: len(relay.levels) > tries, 20, "the console trying to reconnect")
        assert console.command("200")  # typed now, into a console that reaches nothing
        relay.restore()  # the broker reachable again: the console reconnects (1..5 s later)
        assert console.sync(slow(20)), "the console never came back"
        console.publish(f"{BASE}/console/mark", "after")  # sent after its reconnect
        before = watcher.wait_for(f"{BASE}/console/mark", "after")
        late = [m for m in before if m[0] == topics.rotator("rotorez").target]
        assert late == [], f"a bearing typed while cut off reached the broker on reconnect: {late}"
    finally:
        console.close()
        watcher.close()
        relay.close()


def console_through(port: int, topics: Topics, *, mqtt5: bool) -> Console:
    """The demo's console for one rotator on BASE, connected through ``port`` (a relay)."""
    return Console(
        "127.0.0.1",
        port,
        client_id=f"{BASE}-ui",
        topics=topics,
        rotator_ids=["rotorez"],
        discovery_filters=[],
        screen=Screen(),
        mqtt5=mqtt5,
    )
