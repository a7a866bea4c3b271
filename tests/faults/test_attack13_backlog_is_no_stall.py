"""Attack 13's other side: a main connection kept seconds behind by a burst of targets reads its
own heartbeats back late, as from a broker that stalled, yet nothing held it up but itself. The
reverted first design (74d1d147) called the broker late then and refused the burst's newest
target after older ones of the same burst were carried out: the rotor stayed at a target the
user had moved past. The bridge now tells a broker's hold from its own backlog by what its
network thread saw (heartbeat.py rule 11): a backlog never shows quiet, so the newest target
wins (docs/architecture.md rule 11's last word).

The burst is written in one go from a raw socket (a script, a dashboard's slider); the main
connection is kept behind as a slow machine would keep it, once a heartbeat of its own is on
the wire: paho's thread held in the handler of a burst target for QUIET_S + HEARTBEAT_S + 1 s,
a quiet period, not a deadline (it reads nothing meanwhile, the rest of the burst and its beat's
echo wait in its socket). The test asserts that the beat came back that late, so it cannot pass
without the backlog it is about.

Real parts: mosquitto, the bridge in-process, an emulated Rotor-EZ on a pty, a paho probe."""

from __future__ import annotations

import json
import socket
import threading
import time
from typing import Any

from bridge.interfaces.mqtt.heartbeat import HEARTBEAT_S, QUIET_S, Stamp
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

BURST = 3_000
NEWEST = "250"  # the burst's last target (none before it is 250)
KEEP_S = QUIET_S + HEARTBEAT_S + 1.0  # a quiet period, not a deadline: how long it is kept behind
BEAT = "rotor/bridge/heartbeat"


def packet(kind: int, body: bytes) -> bytes:
    """An MQTT 3.1.1 control packet: its fixed header (the remaining length as a varint)."""
    length, n = b"", len(body)
    while True:
        n, digit = n // 128, n % 128
        length += bytes([digit | (0x80 if n else 0)])
        if not n:
            return bytes([kind]) + length + body


def publish(topic: str, payload: bytes) -> bytes:
    """A PUBLISH at QoS 0."""
    name = topic.encode()
    return packet(0x30, len(name).to_bytes(2, "big") + name + payload)


def slide(port: int) -> None:
    """BURST targets, the newest last, in one write on one connection; the broker has them all
    once it answers the PINGREQ written after them."""
    connect = packet(0x10, b"\x00\x04MQTT\x04\x02\x00\x3c\x00\x06slider")
    burst = b"".join(publish("rotor/target", str(100 + i % 140).encode()) for i in range(BURST))
    with socket.create_connection(("127.0.0.1", port), timeout=slow(60)) as s:
        s.sendall(connect)
        assert s.recv(4) == b"\x20\x02\x00\x00", "CONNACK"
        s.sendall(burst + publish("rotor/target", NEWEST.encode()) + b"\xc0\x00")  # + PINGREQ
        assert s.recv(2) == b"\xd0\x00", "PINGRESP"
        s.sendall(b"\xe0\x00")  # DISCONNECT


def test_a_burst_that_keeps_the_main_connection_behind_ends_at_its_newest_target(
    rig: Rig,
) -> None:
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 40.0})
    app = rig.start()
    rig.ready("tower")
    client, paho = app.client, app.client._client
    lock = threading.Lock()
    beats: dict[bytes, float] = {}  # payload -> when the bridge queued it
    backs: dict[bytes, float] = {}  # payload -> when the bridge read it back
    state: dict[str, Any] = {"first": False, "beat": None, "written": False, "kept": None}

    queue_beat = paho.publish

    def publish_beat(topic: str, payload: Any = None, *args: Any, **kwargs: Any) -> Any:
        if topic == BEAT:
            with lock:
                beats[bytes(payload)] = time.monotonic()
                if state["first"] and state["beat"] is None:
                    state["beat"] = bytes(payload)  # the first queued once the burst is read
        return queue_beat(topic, payload, *args, **kwargs)

    write = paho.loop_write

    def loop_write() -> Any:
        rc = write()
        with lock:
            if state["beat"] is not None:
                state["written"] = True  # that beat is on the wire (or in the socket's queue)
        return rc

    intercepted = client._intercepted

    def read_back(topic: str, payload: bytes, retained: bool = False) -> bool:
        if topic == BEAT:
            with lock:
                backs.setdefault(payload, time.monotonic())
        return intercepted(topic, payload, retained)

    handler = client._handler

    def slow_machine(
        topic: str, payload: bytes, retain: bool, operator: str | None, stamp: Stamp | None
    ) -> None:
        if topic == "rotor/target" and payload != NEWEST.encode():
            with lock:
                first, keep = not state["first"], state["written"] and state["kept"] is None
                state["first"] = True
            if first:  # long enough for a beat to be due: it goes after this round
                threading.Event().wait(HEARTBEAT_S + 1.0)  # a quiet period, not a deadline
            elif keep:  # that beat is out: paho's thread reads nothing for KEEP_S
                state["kept"] = time.monotonic()
                threading.Event().wait(KEEP_S)  # a quiet period, not a deadline
        handler(topic, payload, retain, operator, stamp)

    paho.publish = publish_beat  # type: ignore[method-assign]
    paho.loop_write = loop_write  # type: ignore[method-assign]
    client._intercepted = read_back  # type: ignore[method-assign]
    client._handler = slow_machine
    since = rig.probe.mark()
    slide(rig.broker.port)
    rig.arrived("tower", float(NEWEST), timeout_s=60)
    assert state["kept"] is not None, "the main connection was never kept behind"
    beat = state["beat"]
    wait_until(lambda: beat in backs, slow(10), "the bridge read its beat back")
    late_s = backs[beat] - beats[beat]
    assert late_s >= QUIET_S + HEARTBEAT_S, f"its beat came back only {late_s:.1f} s late"
    refused = [
        json.loads(m.payload)
        for m in rig.probe.messages[since:]
        if m.topic == "rotor/error" and b"held this up" in m.payload
    ]
    assert refused == [], refused
    infos = [m.payload for m in rig.probe.messages[since:] if m.topic == "rotor/bridge/info"]
    assert not [i for i in infos if b"holds up" in i], infos
    assert abs(emu.state().az_deg - float(NEWEST)) <= 3
