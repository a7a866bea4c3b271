"""Review 147, finding 2: the demo's console waits for "everything the broker had for us so far"
by a round trip of a sync marker (bridge/demo/console.py ``sync``); since 8dbbaad5 each marker
is unique, so that "an older one back late ends no wait" (review 146 (4)). ``sync`` clears its
event first and only then makes the new marker: an older marker that arrives in between (a sync
that gave up on a slow path, its marker coming back late) is taken for the new one, and the
new wait ends at once, before what the broker had for the console has arrived. The clean-up at
``q`` then computes what to remove from an incomplete picture (a retained message left behind
while the console says it removed them), ``look`` reads no bridge on a base topic that has one.
Older in a wider form: 1998b9a5's marker was always b"sync", and any late one ended any wait.

Real mosquitto (MQTT 5); the console's connection through a relay whose way back from the
broker can be held and let go (a slow path); the older marker let go while the new sync makes
its marker (``secrets.token_hex``, widened till that marker has arrived), then a retained
message published on the broker, held on its way to the console with the new marker.

Fixed: console.py rule 6."""

from __future__ import annotations

import contextlib
import socket
import threading
import types
from typing import Any

import paho.mqtt.client as paho
import pytest

import bridge.demo.console as console_module
from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath


class HeldWayBack(DeadPath):
    """The relay whose way back from the broker can be held (``hold``) and let go, in order
    (``release``): a slow path, nothing lost."""

    def __init__(self, port: int) -> None:
        super().__init__(port)
        self.hold = False
        self.held: list[tuple[socket.socket, bytes]] = []
        self._hold_lock = threading.Lock()

    def _pipe(self, src: socket.socket, dst: socket.socket) -> None:
        with contextlib.suppress(OSError):
            from_broker = src.getpeername()[1] == self.target
            while data := src.recv(65536):
                with self._hold_lock:
                    if self.hold and from_broker:
                        self.held.append((dst, data))
                        continue
                dst.sendall(data)
        with contextlib.suppress(OSError):
            dst.close()

    def holds(self, part: bytes) -> bool:
        with self._hold_lock:
            return any(part in data for _dst, data in self.held)

    def release(self) -> None:
        with self._hold_lock:
            held, self.held, self.hold = self.held, [], False
            for dst, data in held:
                with contextlib.suppress(OSError):
                    dst.sendall(data)


def test_an_older_marker_back_late_does_not_end_a_new_sync(
    broker: Mosquitto, monkeypatch: pytest.MonkeyPatch
) -> None:
    relay = HeldWayBack(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    kept = f"{BASE}/kept/late"
    console = console_through(relay.port, topics, mqtt5=True)
    sync_topic = f"{BASE}/console/sync"
    markers: list[bytes] = []  # the sync markers the console got, in order
    arrived = threading.Condition()
    on_message = console._client.on_message

    def counting(client: paho.Client, u: Any, msg: paho.MQTTMessage) -> None:
        on_message(client, u, msg)  # (the console's own handling first)
        if msg.topic == sync_topic:
            with arrived:
                markers.append(bytes(msg.payload))
                arrived.notify_all()

    new_words: list[str] = []

    def token_hex(n: int) -> str:
        """The new sync makes its marker: the older one, held so far, arrives meanwhile; then
        a retained message is published on the broker (its way to the console held)."""
        with arrived:
            seen = len(markers)
            relay.release()
            assert arrived.wait_for(lambda: len(markers) > seen, slow(20)), "no late marker"
        relay.hold = True
        info = watcher._client.publish(kept, b"x", qos=1, retain=True)
        info.wait_for_publish(slow(20))
        word = f"{147:0{2 * n}x}"
        new_words.append(word)
        return word

    outcome: list[tuple[bool, bytes | None]] = []
    try:
        assert console.sync(slow(20)), "the console never connected through the relay"
        console._client.on_message = counting
        relay.hold = True  # the way back slows down
        assert not console.sync(0.2), "the first marker came back through a held path"
        monkeypatch.setattr(console_module, "secrets", types.SimpleNamespace(token_hex=token_hex))

        def new_sync() -> None:
            ok = console.sync(slow(20))
            outcome.append((ok, console.retained(kept)))

        syncing = threading.Thread(target=new_sync, daemon=True)
        syncing.start()
        wait_until(
            lambda: bool(outcome) or (bool(new_words) and relay.holds(new_words[0].encode())),
            20,
            "the new sync's end, or its marker on the held way back",
        )
        relay.release()  # the path is fast again: what the broker had arrives, then the marker
        syncing.join(slow(20))
    finally:
        console.close()
        watcher.close()
        relay.close()
    assert outcome, "the new sync never ended"
    ok, seen = outcome[0]
    assert ok, "the new sync's own marker never came back"
    assert seen == b"x", (
        "the new sync ended before the retained message the broker had for the console "
        "arrived: an older marker back late ended it"
    )
