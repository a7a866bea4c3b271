"""Review 144, finding 1: since e7d107fa the demo's console sends a typed STOP at QoS 1 "kept
by paho for the next connection" (bridge/demo/console.py rule 3b: "late, they move nothing"),
while a typed bearing goes at QoS 0, now or never. When the broker's PUBACK for the STOP is lost
(the path back from the broker goes dead: a Wi-Fi drop, a NAT that forgot the flow), the STOP
and the bearing typed after it both reach the broker and the bridge at once, the rotor stops and
then turns to the new bearing; on the reconnect paho sends the unacknowledged STOP again, alone,
and the turn the user asked for after it is stopped short seconds later. Neither parent does
this: 725af295 sent the STOP at QoS 0 (never again), 16dff1c0 sent both at QoS 1 and paho sent
them again in their order (the bearing last).

Real mosquitto (MQTT 5, the demo's usual broker); the console's connection through a relay
whose way back from the broker carries nothing, then closed; what reaches the broker read by an
MQTT 3.1.1 client there, as the bridge would get it."""

from __future__ import annotations

import contextlib
import socket

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath


class DeadWayBack(DeadPath):
    """The relay whose way back from the broker can carry nothing (``back_dead``): what the
    console sends arrives, what the broker answers (its PUBACKs) does not."""

    def __init__(self, port: int) -> None:
        super().__init__(port)
        self.back_dead = False

    def _pipe(self, src: socket.socket, dst: socket.socket) -> None:
        with contextlib.suppress(OSError):
            from_broker = src.getpeername()[1] == self.target
            while data := src.recv(65536):
                if self.dead or (self.back_dead and from_broker):
                    self.dropped += len(data)
                else:
                    dst.sendall(data)
        with contextlib.suppress(OSError):
            dst.close()


def test_a_stop_typed_before_a_bearing_is_not_sent_again_after_it_on_reconnect(
    broker: Mosquitto,
) -> None:
    relay = DeadWayBack(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    r = topics.rotator("rotorez")
    console = console_through(relay.port, topics, mqtt5=True)
    try:
        assert console.sync(slow(20)), "the console never connected through the relay"
        tries = len(relay.levels)
        relay.back_dead = True  # the broker's answers go nowhere; nobody has noticed yet
        assert console.command("s")
        watcher.wait_for(r.stop, "STOP")
        assert console.command("120")  # the next turn, typed after the stop
        watcher.wait_for(r.target, "120")
        relay.cut()  # the dead connection found out at last: closed
        relay.back_dead = False
        wait_until(lambda: len(relay.levels) > tries, 20, "the console trying to reconnect")
        relay.restore()
        assert console.sync(slow(20)), "the console never came back"
        console.publish(f"{BASE}/console/mark", "after")
        got = watcher.wait_for(f"{BASE}/console/mark", "after")
        commands = [m for m in got if m[0] in (r.stop, r.target)]
        assert commands[-1] == (r.target, "120"), (
            f"the turn to 120 typed after the STOP is stopped by the STOP sent again: {commands}"
        )
    finally:
        console.close()
        watcher.close()
        relay.close()
