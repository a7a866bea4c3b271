"""The floor's engine (benchmarks/floor.py): the least a process can do per poll exchange of the
exchange_cpu scenario, written for the measurement only, never a bridge.

    python -m benchmarks.floor_engine --port PORT --base rotor --rotator ID=PATH ...
        [--paho inline|thread] [--read os|pyserial] [--status on|off] [--mqtt on|off]
        [--gather whole|bytes] [--gather-ms MS] [--extra-wakes N]

Rules:
1. One thread (and paho's own with ``--paho thread``), one selector over the ports and, with
   ``--paho inline``, paho's socket. Every POLL_S it writes ``AI1;`` to every port at once; a
   reply is taken when its four bytes ``;xxx`` are in, and its bearing published at once:
   ``BASE/ID/bearing`` (the bare number) and, with ``--status on``, a small JSON status on
   ``BASE/ID/status``, both retained at QoS 0, as the bridge publishes state. Nothing else: no
   checks, no timeouts, no commands, no log; what a real engine must do besides is what the
   floor leaves out.
2. ``--paho inline``: paho driven from the same thread through its external-loop API
   (``loop_read`` when the socket is readable, ``loop_write`` while ``want_write``,
   ``loop_misc`` once a second); without ``loop_start`` paho's ``publish`` writes the packet
   at once (no socket pair, no wake-up). ``--paho thread``: paho's own ``loop_start``.
3. ``--read pyserial``: each port opened and read through pyserial (``Serial.read`` of what
   ``in_waiting`` says); ``--read os``: opened by pyserial too (its settings), read with
   ``os.read`` on its descriptor. Queries are written with ``os.write`` either way.
4. Once connected and every port open it publishes ``BASE/ID/availability`` ``online``
   (retained, QoS 1) for each rotator: the benchmark's sign that it runs.
5. ``--gather whole`` (the default): the ports are read GATHER_S (``--gather-ms``) after the
   queries, when the replies are whole, as the bridge reads a reply in one go once its time on
   the line is over; a port whose reply is not whole then is watched until it is. ``--gather
   bytes``: every port is watched all the time and read as each byte comes (a wake-up per
   byte). It publishes ``BASE/floor/stats``, "wake-ups reads" so far, once a second.
6. ``--extra-wakes N``: N more wake-ups a poll cycle (50, 80, 110 and 140 ms after the
   queries) that do nothing but wake: what a wake-up of the thread costs by itself.
7. ``--mqtt off``: a reading's messages are made (the status encoded) and not handed to paho:
   what the serial side and the loop cost alone.
"""

from __future__ import annotations

import argparse
import json
import os
import selectors
import sys
import time
from datetime import UTC, datetime
from typing import Any

import paho.mqtt.client as paho
import serial

POLL_S = 0.2  # the bridge's poll interval for a turning rotor
QUERY = b"AI1;"
BAUD = 4800
#: a query's 4 bytes and a reply's 4 at 4800 baud (10 bits a byte) take 16.7 ms on the line;
#: with the controller's and the paced line's own time, most replies are whole by 30 ms (at 20
#: ms, two or three reads an exchange were made: half the replies came in part)
GATHER_S = 0.030


def _nothing(*_args: object) -> None:
    """``--mqtt off``: a reading's messages are made, and not handed to paho."""


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.floor_engine")
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--base", default="rotor")
    ap.add_argument("--client-id", default="floor")
    ap.add_argument("--rotator", action="append", required=True, metavar="ID=PATH")
    ap.add_argument("--paho", choices=("inline", "thread"), default="inline")
    ap.add_argument("--read", choices=("os", "pyserial"), default="os")
    ap.add_argument("--status", choices=("on", "off"), default="on")
    ap.add_argument("--gather", choices=("whole", "bytes"), default="whole")
    ap.add_argument("--gather-ms", type=float, default=GATHER_S * 1000)
    ap.add_argument("--mqtt", choices=("on", "off"), default="on")
    ap.add_argument("--extra-wakes", type=int, default=0, choices=range(5))
    args = ap.parse_args(argv)

    client = paho.Client(
        paho.CallbackAPIVersion.VERSION2, client_id=args.client_id, protocol=paho.MQTTv5
    )
    client.connect("127.0.0.1", args.port, keepalive=60)
    inline = args.paho == "inline"
    if not inline:
        client.loop_start()
    sel = selectors.DefaultSelector()
    ports = []
    for spec in args.rotator:
        rid, path = spec.split("=", 1)
        ser = serial.Serial(path, BAUD, timeout=0)
        fd = ser.fileno()
        slot: dict[str, Any] = {
            "ser": ser,
            "fd": fd,
            "buf": b"",
            "watched": args.gather == "bytes",
            "bearing_topic": f"{args.base}/{rid}/bearing",
            "status_topic": f"{args.base}/{rid}/status",
        }
        ports.append(slot)
        if args.gather == "bytes":
            sel.register(fd, selectors.EVENT_READ, slot)
    sock = client.socket() if inline else None
    if inline:
        assert sock is not None
        sel.register(sock, selectors.EVENT_READ, None)
        while not client.is_connected():  # the CONNACK
            client.loop_read()
            client.loop_write()
    for spec in args.rotator:
        rid = spec.split("=", 1)[0]
        client.publish(f"{args.base}/{rid}/availability", b"online", qos=1, retain=True)

    encode = json.JSONEncoder(separators=(",", ":")).encode
    status_on = args.status == "on"
    pyserial_read = args.read == "pyserial"
    whole = args.gather == "whole"
    gather_s = args.gather_ms / 1000
    publish = client.publish if args.mqtt == "on" else _nothing
    os_read, os_write = os.read, os.write
    stats_topic = f"{args.base}/floor/stats"
    wakes = reads = 0
    writing = False
    pending: list[dict[str, Any]] = []  # rule 5: read at gather_at
    gather_at = 0.0
    next_poll = time.monotonic()
    next_misc = next_poll + 1.0
    stamp = ""
    extra: list[float] = []  # rule 6: wake-ups that do nothing

    def take(p: dict[str, Any]) -> bool:
        """Reads what the port has; publishes a whole reply; True once the reply is in."""
        nonlocal reads
        reads += 1
        try:
            if pyserial_read:
                ser = p["ser"]
                data = ser.read(ser.in_waiting or 1)
            else:
                data = os_read(p["fd"], 64)
        except BlockingIOError:
            data = b""
        buf = p["buf"] + data
        if len(buf) < 4:
            p["buf"] = buf
            return False
        p["buf"] = b""
        if buf[0] != 0x3B:
            return True
        bearing = int(buf[1:4])
        publish(p["bearing_topic"], str(bearing), 0, True)
        if status_on:
            status = {
                "bearing": float(bearing),
                "target": None,
                "parked": False,
                "state": "moving",
                "moving": True,
                "connected": True,
                "available": True,
                "locked": False,
                "version": "1.4S",
                "options": {},
                "last_error": None,
                "last_command_source": "mqtt",
                "last_operator": "mqtt",
                "control": None,
                "estimated": False,
                "time": stamp,
            }
            publish(p["status_topic"], encode(status), 0, True)
        return True

    while True:
        now = time.monotonic()
        if now >= next_poll:
            for p in ports:
                p["buf"] = b""
                os_write(p["fd"], QUERY)
            if whole:
                for p in ports:
                    if p["watched"]:
                        sel.unregister(p["fd"])
                        p["watched"] = False
                pending = list(ports)
                gather_at = now + gather_s
            next_poll += POLL_S
            if next_poll < now:
                next_poll = now + POLL_S
            stamp = datetime.now(UTC).isoformat(timespec="milliseconds")
            extra = [now + 0.050 + 0.030 * k for k in range(args.extra_wakes)]
        while extra and now >= extra[0]:
            extra.pop(0)
        if pending and now >= gather_at:
            for p in pending:
                if not take(p):  # not whole yet: its next bytes wake us
                    sel.register(p["fd"], selectors.EVENT_READ, p)
                    p["watched"] = True
            pending = []
        if inline:
            if now >= next_misc:
                client.loop_misc()
                next_misc = now + 1.0
                client.publish(stats_topic, f"{wakes} {reads}", 0, True)
            want = client.want_write()
            if want != writing:
                sel.modify(sock, selectors.EVENT_READ | (selectors.EVENT_WRITE if want else 0))
                writing = want
        elif now >= next_misc:
            next_misc = now + 1.0
            client.publish(stats_topic, f"{wakes} {reads}", 0, True)
        until = min(next_poll, gather_at) if pending else next_poll
        if extra:
            until = min(until, extra[0])
        events = sel.select(max(0.0, until - time.monotonic()))
        wakes += 1
        for key, mask in events:
            p = key.data
            if p is None:  # paho's socket
                if mask & selectors.EVENT_READ:
                    client.loop_read()
                if mask & selectors.EVENT_WRITE:
                    client.loop_write()
            elif take(p) and whole:
                sel.unregister(p["fd"])
                p["watched"] = False


if __name__ == "__main__":
    sys.exit(main())
