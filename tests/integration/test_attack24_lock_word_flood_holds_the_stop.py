"""Attack 24: a flood on ``R/lock`` from another client keeps an operator's STOP from the wire for
seconds, past the whole turn.

The stop lane exists so that "no flood of targets from other clients" delays a stop (README,
Safety; docs/mqtt.md, three connections): it subscribes to ``R/stop`` and ``R/lock`` alone. But
the lock words come on the lane too, one per message, every one read and judged in turn there
(halts.py ``on_lane``: a lock OFF takes the last word's lock, shared with the main connection,
which carries out each OFF in order as an owner's step, a save and an audit line), and on the
main connection as well. A client that republishes ``R/lock`` ``OFF`` in a loop (two
automations fighting over a switch: docs/reliability.md knows 400 ``R/lock ON`` from one) fills
the lane faster than it reads: a STOP published behind that flood, by Home Assistant's button
on its own connection, waits on the lane and on the main connection behind every word of it.
The stop express (its own process, which would write the stop at once) gets no copy of a
DCU-1's port (``ModelSpec.stop_anytime``), nor of a SPID's, a SatEL's, an RC2800's, an
RT-21's or a Prosistel's, and is off with ``mqtt.stop_express = false``.

Measured here (a DCU-1 turning at 20 degrees a second, the express on, the bridge's default):
the DCU-1's ``AS1;`` went 2.2 s after the STOP with ``OFF`` at 10,000 messages a second, 9.9 s
at 20,000 (``junk`` in place of ``OFF``: 5.1 s); as fast as one client can, the STOP never
went before the rotor reached the target it was stopped on the way to. The same flood on
``R/target``: the stop in 7 ms.

The test keeps the flood going as fast as the broker takes it and sends the STOP once the
bridge has read a share of it, the rotor turning from 20 to 300; it asserts the end, not a
time: the rotor rests where the STOP caught it, short of 300 (the control: so it does behind
the same flood on ``R/target``).

Fixed by giving the lock words a lane of their own (interfaces/mqtt/lastword.py rule 16): the
stop lane carries ``R/stop`` and ``G/stop`` alone, and a flood of lock words delays only the
lock words behind it.

Real parts: mosquitto, the bridge (App), an emulated DCU-1 on a pty."""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bridge.interfaces.mqtt.heartbeat import Stamp
from tests.integration.test_stop_after_backlog import packet, publish
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

GOAL_DEG = 300  # the turn the STOP is sent in, from 20
STOP_BEFORE_DEG = 150  # the STOP is published while the rotor is short of this...
SHORT_OF_DEG = 220  # ... and a STOP carried out promptly leaves it resting short of this
READ_FIRST = 5_000  # flood messages the bridge has read when the STOP is published: it is on
BURST = 2_000  # lock words a write of the flooding client
FINITE_BURSTS = 15  # a flood that ends (30,000 lock OFFs), and then the lock ON


class Flood:
    """A client that publishes ``payload`` on ``topic`` at QoS 0 as fast as the broker takes
    it, on a thread, until ``end`` (or ``bursts`` writes of BURST)."""

    def __init__(self, port: int, topic: str, payload: bytes, bursts: int | None = None) -> None:
        self._topic = topic
        self._bursts = -1 if bursts is None else bursts  # (-1: until ``end``)
        self._burst = b"".join(publish(topic, payload) for _ in range(BURST))
        self._sock = socket.create_connection(("127.0.0.1", port), timeout=slow(30))
        self._sock.sendall(packet(0x10, b"\x00\x04MQTT\x04\x02\x00\x3c\x00\x07flooder"))
        assert self._sock.recv(4) == b"\x20\x02\x00\x00", "CONNACK"
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, name="lock-flood", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            while not self._done.is_set() and self._bursts != 0:
                self._sock.sendall(self._burst)
                self._bursts -= 1
        except OSError:
            pass  # (closed by ``end``)

    def end(self, last: bytes | None = None) -> None:
        """The flood over; ``last``: one more message on its topic, published after every
        one of the flood (its own socket: the broker takes them in that order)."""
        self._done.set()
        self._thread.join(slow(10))
        if last is not None and not self._thread.is_alive():
            self._sock.sendall(publish(self._topic, last))
            self._sock.sendall(packet(0xC0, b""))  # PINGREQ: its answer says all was taken
            assert self._sock.recv(2) == b"\xd0\x00", "PINGRESP"
        self._sock.close()


@dataclass
class Bench:
    """A broker, the probe on it, the bridge (App) with ``tower``, an emulated DCU-1, and the
    operator's own connection; ``flood``: the one under way, ended with the bench."""

    broker: Mosquitto
    probe: Probe
    rig: Rig
    operator: Probe
    emu: Any
    app: Any
    flood: Flood | None = None


@contextmanager
def flooding_bench(tmp_path: Path, topics: str, speed_deg_s: float) -> Iterator[Bench]:
    """The bench (the probe on ``topics``), the rotor at 20 turning at ``speed_deg_s``; all
    closed after, a flood under way ended first."""
    broker = Mosquitto(tmp_path / "broker")
    broker.start()
    probe = Probe(broker.port, topics)
    rig = Rig(tmp_path, broker, probe)
    rig.express = None  # the bridge's own default: the stop express on
    operator = Probe(broker.port, "")
    bench: Bench | None = None
    try:
        emu: Any = rig.add("tower", "dcu1", emu={"start_az_deg": 20, "speed_deg_s": speed_deg_s})
        app = rig.start()
        rig.ready("tower")
        bench = Bench(broker, probe, rig, operator, emu, app)
        yield bench
    finally:
        if bench is not None and bench.flood is not None:
            bench.flood.end()
        operator.close()
        rig.close()
        probe.close()
        broker.stop()


def counted_reads(
    app: Any, topic: str, then: Callable[[str, bytes], None] | None = None
) -> list[int]:
    """The main connection's reads of ``topic`` counted (the one item of the list returned);
    ``then``: told every message after the bridge's handler took it."""
    read = [0]
    on_main = app.client._handler

    def counted(
        seen: str, data: bytes, retain: bool, sender: str | None, stamp: Stamp | None
    ) -> None:
        if seen == topic:
            read[0] += 1
        on_main(seen, data, retain, sender, stamp)
        if then is not None:
            then(seen, data)

    app.client._handler = counted
    return read


def stop_in_a_flood(tmp_path: Path, topic: str, payload: bytes) -> None:
    """The rotor turning from 20 to GOAL_DEG, a flood of ``payload`` on ``topic`` under way (the
    main connection has read READ_FIRST of it), the operator's STOP: the rotor rests short of
    SHORT_OF_DEG."""
    with flooding_bench(tmp_path, "rotor/availability|rotor/state|rotor/error", 20.0) as bench:
        broker, operator, emu, app = bench.broker, bench.operator, bench.emu, bench.app
        wait_until(app.lane.connected.is_set, 10, "the lane is up")
        read = counted_reads(app, topic)
        operator.publish("rotor/target", str(GOAL_DEG).encode())
        emu.wait_for(lambda s: s.is_moving, slow(10))
        bench.flood = Flood(broker.port, topic, payload)
        wait_until(lambda: read[0] >= READ_FIRST, 30, "the bridge reads the flood")
        at_stop = emu.state()
        assert at_stop.is_moving and at_stop.az_deg < STOP_BEFORE_DEG, at_stop  # (in the turn)
        frames_before = len(emu.log())
        operator.publish("rotor/stop", b"STOP")  # Home Assistant's button, its own connection
        rest = emu.wait_for(lambda s: not s.is_moving, slow(60))
        stops = [f.data for f in emu.log()[frames_before:] if f.data == b"AS1;"]
        assert rest.az_deg < SHORT_OF_DEG, (
            f"STOP published at {at_stop.az_deg:.0f} degrees; the rotor came to rest at "
            f"{rest.az_deg:.0f} (stop frames since: {len(stops)})"
        )


def test_control_a_stop_behind_a_flood_of_targets_stops_the_rotor_where_it_was(
    tmp_path: Path,
) -> None:
    """The same flood on the main connection alone (a target it refuses): the lane's STOP."""
    stop_in_a_flood(tmp_path, "rotor/target", b"junk")


def test_a_stop_behind_a_flood_of_lock_words_stops_the_rotor_where_it_was(
    tmp_path: Path,
) -> None:
    stop_in_a_flood(tmp_path, "rotor/lock", b"OFF")


def test_a_lock_on_after_a_flood_of_lock_offs_halts_the_rotor_and_stays_on(tmp_path: Path) -> None:
    """The lock words moved to a lane of their own (lastword.py rule 16): a lock ON published
    after a flood of lock OFFs (by the flooding client itself, so the broker had every OFF
    first) is still the last word on every connection that reads it. The rotor, turning from
    20 to GOAL_DEG, is stopped short of it; once the main connection has read the whole
    flood, the ON and a target after them, the lock is still ON in the bridge and in its
    retained R/lock/state, and the rotor has not moved. (Measured here: locked about 2 s
    after the ON, the lock lane reading the 30,000 OFFs ahead of it.)"""
    topics = "rotor/availability|rotor/state|rotor/error|rotor/lock/state"
    with flooding_bench(tmp_path, topics, 5.0) as bench:
        broker, probe, operator, emu, app = (
            bench.broker,
            bench.probe,
            bench.operator,
            bench.emu,
            bench.app,
        )
        wait_until(app.lock_lane.connected.is_set, 10, "the lock lane is up")
        main_read_target = threading.Event()

        def judged(seen: str, data: bytes) -> None:
            if seen == "rotor/target" and data == b"100":
                main_read_target.set()  # (judged: its refusal, or its put, is done)

        read = counted_reads(app, "rotor/lock", then=judged)
        operator.publish("rotor/target", str(GOAL_DEG).encode())
        emu.wait_for(lambda s: s.is_moving, slow(10))
        # (a flood the broker drops none of, for a reader behind: its queue, QoS 0, would as
        # well drop the ON, which then never comes, as a target after a flood: reliability.md)
        flood = Flood(broker.port, "rotor/lock", b"OFF", bursts=FINITE_BURSTS)
        bench.flood = flood
        wait_until(lambda: read[0] >= READ_FIRST, 30, "the bridge reads the flood")
        flood.end(last=b"ON")
        bench.flood = None
        rotator = app.rotators[0]
        wait_until(lambda: rotator.status.locked, 60, "the lock ON after the flood")
        rest = emu.wait_for(lambda s: not s.is_moving, slow(60))
        assert rest.az_deg < GOAL_DEG - 10, rest  # (stopped by the ON, not at the target)
        probe.wait_value("rotor/lock/state", "ON", slow(30))
        # a target after it: once the main connection has judged it, it has read the whole
        # flood and the ON (each OFF refused as older than the lane's ON: lastword.py rule 8),
        # and the lock is still ON: the target was refused by it (or by the ON's hold)
        operator.publish("rotor/target", b"100")
        wait_until(main_read_target.is_set, 60, "the main connection reads the target")
        assert rotator.locked and rotator.status.locked
        assert [m.text for m in probe.on("rotor/lock/state")][-1] == "ON"
        assert not emu.state().is_moving
