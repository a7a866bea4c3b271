"""Review 139, finding 1: since 725af295 the demo's console sends every typed line at QoS 0
("now or never", bridge/demo/console.py rule 3b, review 134 (1)), the STOP typed as ``s``
included. A stop cannot move a rotor, so the reason for "never later" (a stale bearing turning
the rotor on reconnect) does not hold for it, and the house's first rule says a STOP must always
get through. On a connection that went dead without paho knowing yet (a Wi-Fi drop, a NAT that
forgot the flow: ``is_connected()`` still says yes), the QoS 0 STOP goes into a socket that
carries nothing, the console says nothing, and when it reconnects the STOP is gone: the rotor
runs on to its target. Its parent (16dff1c0) sent it at QoS 1, unacknowledged, so paho sent it
again on the next connection and the rotor stopped.

Real mosquitto (MQTT 5, the demo's usual broker); the console's own connection runs through a
relay that first carries nothing (the dead path) and is then closed; what reaches the broker
is read by an MQTT 3.1.1 client there."""

from __future__ import annotations

import contextlib
import socket

from bridge.demo.console import Console
from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import (
    BASE,
    Cuttable,
    Watcher,
    console_through,
)


class DeadPath(Cuttable):
    """The relay, passing MQTT 5 too, that can also carry nothing while its sockets stay open
    (a path gone dead: the client's writes are taken and never arrive)."""

    def __init__(self, port: int) -> None:
        super().__init__(port)
        self.v5_closes_left = 0
        self.dead = False
        self.dropped = 0  # bytes taken while dead

    def cut(self) -> None:
        """Closed, both ways, so that each end sees it at once (a close alone waits for the
        relay's reads)."""
        with self._lock:
            socks = list(self._socks)
        for s in socks:
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)
        super().cut()

    def _pipe(self, src: socket.socket, dst: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                if self.dead:
                    self.dropped += len(data)
                else:
                    dst.sendall(data)
        with contextlib.suppress(OSError):
            dst.close()


def test_a_stop_typed_on_a_dead_connection_reaches_the_broker_once_the_console_reconnects(
    broker: Mosquitto,
) -> None:
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        before = typed_on_a_dead_path(console, relay, watcher, "s", "STOP")
        stops = [m for m in before if m[0] == topics.rotator("rotorez").stop]
        assert stops == [(topics.rotator("rotorez").stop, "STOP")], (
            f"the STOP typed on the dead connection never reached the broker: {before}"
        )
    finally:
        console.close()
        watcher.close()
        relay.close()


def typed_on_a_dead_path(
    console: Console, relay: DeadPath, watcher: Watcher, line: str | list[str], what: str
) -> list[tuple[str, str]]:
    """``line`` (or each of the lines, in turn) typed on the console while ``relay`` carries
    nothing (a PUBLISH, the first's, the ``what``'s, taken by the dead path), then the dead
    connection found out and the console back: what reached the broker before the console's
    mark after it."""
    assert console.sync(slow(20)), "the console never connected through the relay"
    tries = len(relay.levels)
    relay.dead = True  # the path carries nothing; nobody has noticed yet
    for typed in [line] if isinstance(line, str) else line:
        assert console.command(typed)
    wait_until(lambda: relay.dropped > 0, 20, f"the {what}'s PUBLISH taken by the dead path")
    relay.cut()  # the dead connection found out at last: closed
    relay.dead = False
    wait_until(lambda: len(relay.levels) > tries, 20, "the console trying to reconnect")
    relay.restore()
    assert console.sync(slow(20)), "the console never came back"
    console.publish(f"{BASE}/console/mark", "after")
    return watcher.wait_for(f"{BASE}/console/mark", "after")
