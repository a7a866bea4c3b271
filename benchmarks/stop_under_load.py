"""Stops beside each load the stop's promise names: "a STOP reaches the controller within 10 ms
whatever else runs" (p99), and the stop's tail against the engine of 2026-11-26.

    python -m benchmarks stop_under_load            # 60 stops per load, 300 pairs per engine
    python -m benchmarks stop_under_load --quick    # 20 stops per load, 60 pairs per engine

The loaded bridge: a private mosquitto (no limit on the messages it queues for a client, so
that the whole backlog reaches the bridge: its default 1000 would drop a large one) and one
bridge as its own service process with everything a load needs switched on: MEASURED Rotor-EZ
(m0..) emulated in this process behind lines paced at 4800 baud (turning at 45 deg/s, 0.5 s
brake; the bridge is told the same and polls an idle one every 0.5 s), m0 with a rotctld, a
GS-232 and an Easycomm TCP port, a PstRotator and an N1MM UDP port; the backlog's Rotor-EZ
``b`` (1 s brake, as on a Ham-IV) and ``d`` (the backlog's end marker), in this process too;
8 MD-01 in the emulator host (t0..t7, for tracking and the console's commands); ``[station]``
and ``[tracking]`` with a TLE file, ``[web]``, ``[wsjtx]`` and ``[dxcluster]`` pointing at a
fake node this benchmark serves on loopback (its own process, started before the bridge and
quiet until its load).

One stop: a measured rotor is turned far from its front panel (the emulator; no MQTT target,
which could queue behind a load on the main connection); once the emulator turns and the
bridge says ``moving``, 0-200 ms later (a moving poll's period: a stop lands anywhere in the
poll cycle, not just after a reply), ``R/stop`` ``STOP <n>`` (QoS 1, not retained) from a client
of its own (it never queues behind a loader's messages). The latency is from that publish to
the complete stop frame ``;`` at the controller (the emulator's log, on our clock: the same
CLOCK_MONOTONIC as every process here), so it includes the byte's own 2.1 ms on the line and
any exchange in flight. The paced line hands the bytes to the emulator in this process, not
through the emulator's pty (benchmarks/line.py rule 5): a pty passes them on from a kernel
worker at nice 0, which under these loads waited for a CPU up to tens of ms after the line
had delivered the byte (a real UART has no such hop). The bridge's own port is still a pty:
its write reaches the line through that worker too, so every row says how long that hop took
on this machine while its stops were taken (``pty hop``: a probe writing a byte through a pty
of its own every 5 ms, benchmarks/ptyhop.py), and the focused mode below shows it per stop.
``STOP_VIA_PTY=1`` puts the controllers' ptys back on the path (the hop left out, to compare).
``STOP_EXPRESS=0`` runs this tree's bridges without the stop express (``mqtt.stop_express``
off: the stop's frame written by the bridge's process alone), to compare in turns.
``STOP_ONLY=trackings`` takes the control and the trackings only (no other load, no pairs; with
``STOP_TRACE`` too): a few minutes, to compare one load's tail in runs taken in turns;
``STOP_ONLY=backlog`` the control and the backlog (its rounds, the round alone and its table);
``STOP_ONLY=rotctld`` (``gs232``, ``easycomm``) the control and that port's 16 TCP clients.
The instrument does not wait behind the loads it creates (benchmarks/harness.py rule 6): where
the system allows it, every thread of this process (the controllers' emulators and paced lines
that carry and stamp the stop frame, the stops' publisher, the probes, the taker that may hold
the interpreter lock they wait for) runs in the real-time class, as a controller's
microcontroller and UART would; at nice -10 (rule 5), in traced backlog runs, a relay waited
14 ms in the run queue with the stop byte due, and another 14.5 ms off it (for the interpreter
lock: our other threads, which may hold it, waited for a core up to 7.6 ms). Every stop keeps
``stamp_late``, how long after the line delivered its byte the controller stamped the frame
(benchmarks/line.py rule 8): the instrument's own wait, inside the latency, in its own column;
a relay late to read the bridge's byte moves that byte's due time, so such a wait is in the
bridge's part instead (with STOP_TRACE, ``pty hop`` in the analysis's split).
``STOP_INSTRUMENT_RT=0`` leaves those threads at nice -10, to compare; the latency counts the
same either way. The broker, the bridge and its express, the kernel's pty worker and the loads
keep their priorities.
``BRIDGE_NICE=5`` lowers every thread of the loaded bridge's process to that nice value once its
stop express is up (the express keeps nice 0): whether the host's other work (the broker, the
pty's kernel worker, the express) then waits less behind the bridge's busy threads.
The rotors take turns; one stop is in flight at a time.

The line's own floor: a stop can find the line still sending bytes the bridge wrote before the
STOP was published, most often the poll query ``AI1;`` the bridge sends every 0.2 s while the
rotor turns (4 bytes, 8.3 ms at 4800 baud, 2.08 ms a byte). Bytes handed to a UART cannot be
called back, and a Rotor-EZ stop is a bare ``;``: flushing a query sent in part would join its
rest and the ``;`` into one junk frame and lose the stop. A stop right behind a whole query takes
8.3 + 2.1 = 10.4 ms whatever the bridge does; a query holds the line 8.3 ms in every 200, and
with 60 stops the p99 is the largest. So each stop's ``wire_ahead`` is kept: how long after its
publish the paced line was still busy with bytes it had read from the bridge before the
publish (the line's due times, on this process's CLOCK_MONOTONIC like the publish stamp:
benchmarks/line.py rule 7), and what those bytes were; and the same at the moment the broker
handed the STOP over (below): ``handed_ahead``, the line busy after the hand-over with bytes it
had read before it. Until then the bridge cannot know of the stop, so a query it writes in
between (its poll grid came round while the broker still passed the STOP on) is the line's
floor too; bytes the bridge wrote after the hand-over, or that reached the line after it (the
bridge's pty hop), count as the bridge's (the bytes read from the publish and from the
hand-over to the stop frame are kept too: ``line_after_publish``, ``line_after_hand_over``).
Polling less often while
turning would only make such a stop rarer, at the cost of a staler bearing, so the bridge keeps
its 0.2 s. Here few stops meet a query: the poll that saw a panel turn was timed on the idle
grid (0.5 s; bridge/session/link.py rule 8), so the first moving poll comes 0.25 s or more after
it, and a stop comes within about 0.22 s of it unless its taker was held up (the trackings'
wait for their round of ``R/track``, a busy machine).

The broker's floor: the bridge cannot act on a STOP before the broker hands it over, and
mosquitto (one thread) passes messages on in the order they came: under the backlog it may still
be passing on the targets published before the STOP. So each stop's ``broker`` is kept too: from
the publish (our client's own send, then the broker's queue) to the moment the broker handed
this STOP to a subscriber of ours (benchmarks/delivery.py: raw MQTT on a thread of this process,
the kernel's receive stamp converted to our CLOCK_MONOTONIC within a few microseconds, so that
thread's own waits do not count), subscribed to the measured rotors' exact stop topics before
the bridge started, so served before the bridge's connections: its time is the earliest
delivery, never later than the bridge's. Each measured STOP's payload is ``STOP <n>``, its own
(any payload on ``R/stop`` is a stop: bridge/interfaces/mqtt/service.py rule 2), which matches a
delivery to its stop. The stop's frame cannot start on the line before the broker handed the
STOP over, nor before the line is free of what the bridge wrote until then: its floor is
broker + handed_ahead (wire_ahead when the probe missed it), and the bridge's part is the
latency less that floor: everything from that moment on (the bridge's own steps, its pty's
hop, the stop byte's own 2.1 ms on the line). The bridge's connections get the STOP after the
probe, so the broker's floor never
counts the broker's time with the bridge's connections as the broker's; but it does count
mosquitto waiting for a core, which the bridge's own busy threads may hold (the backlog's
reader uses about half a core): on a 2-core host that share of the broker's time is the
bridge's load too, and the bridge's part can understate it by that much. A stop
whose delivery the probe did not see (its connection ended: it never reconnects, which would put
it last) keeps the line's floor alone and is counted (``broker_missed``), never dropped. Each
row gives the raw p50/p99/max first (what the promise judges: publish -> ``;``), the broker's
p99, how many stops found bytes ahead (how many of those a poll query), and the p99 of the
bridge's part, which the goal judges; its verdict says when the raw p99 misses the goal while
the bridge's part meets it, and how many of the stops over the goal waited longer for the broker
and how many for the line.

The loads, one after the other, each in a process of its own (our process hosts the emulators,
whose timestamps must not wait behind a load), each started about a second before its stops;
what a load left queued in the kernel (/proc/net) is read by the bridge before the next one
starts, and how long that took is said in its row:
- no load: the control, first, in the same run;
- a 60,000-target backlog: rounds of 60,000 valid targets (QoS 0) to ``b`` on one connection,
  then on the same connection ``b``'s STOP (QoS 1) and a target to ``d`` (the round's end: the
  main connection has read the whole round when ``d`` gets it). Stops are taken while a round
  is being read, and each round is watched until TAIL_S after its end: every move frame ``b``
  gets after its stop frame is a start after the STOP (reported; there must be none). Last, a
  round alone (no measured stop beside it: each of those is a halt with a hold of its own),
  with as many targets as keep the bridge reading HOLD_S after the STOP, at least 60,000 (a
  timeout shorter than that which let the targets out would show here on a fast machine);
- rotctld, GS-232, Easycomm: 16 TCP clients on m0's port each, 12 streaming bytes with no line
  end, 4 sending position queries as fast as the bridge reads them, reconnecting when closed;
- PST, N1MM and WSJT-X: UDP datagrams at UDP_RATE a second in all, the loggers' junk
  (benchmarks/logger_flood.py) to m0's PST and N1MM ports, WSJT-X Status and Heartbeat from ever
  new instance names and junk to the WSJT-X port;
- a DX cluster node sending, as fast as the bridge reads, blocks of spots with hostile lines in
  them (a ``DX de`` line of spaces with no time, over-long lines, telnet bytes, junk);
- the console: 10 pages (the page's requests, then its WebSocket feed read to the end, again
  when it closes) and 8 clients posting commands as fast as they are answered (targets to
  the MD-01s, bad JSON, unknown keys, no token);
- 8 satellite trackings starting: before each stop (0-50 ms before it; these stops come
  TRACK_GAP_S or more apart, one event at a time) the 8 MD-01s get ``R/track`` with the
  elements of a satellite new to the bridge.

Also, on a bridge and broker of their own, the stop's tail against the engine of 2026-11-26
(commit OLD_COMMIT, its ``bridge/`` taken out of git into the work directory and run with its
own import path): PAIR_ROTORS Rotor-EZ per engine, each pair an ``R/target`` far away and,
once the rotor turns, ``R/stop`` as above; the two engines' rotors take turns, so both meet the
same machine. Each engine's worst stop over the pairs is compared.

The machine is shared (2 cores): every row carries the load average over its stops, and the
bridge's CPU over them.

Where an outlier waits (a focused mode: the control, the backlog, the console, the trackings)::

    STOP_TRACE=/tmp/t.json PYTHONPATH=benchmarks/stoptrace_site \
        python -m benchmarks stop_under_load --quick
    python -m benchmarks.stop_trace /tmp/t.json /tmp/t.json.samples.json

the bridge stamps each stop's steps (benchmarks/stop_trace.py) and the analysis sets them
against each stop's publish and its ``;`` at the emulator; for each stop over 9 ms it also
shows what the stop's line carried from 50 ms before the publish (the relay's reads of the
bridge's bytes and its deliveries, the controller's frames, and how long each of those threads
waited for a CPU), from <file>.lines.json.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import json
import math
import os
import random
import select
import socket
import subprocess
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmarks.delivery import DeliveryProbe
from benchmarks.engines import engine_at, engine_env
from benchmarks.harness import (
    ABORT,
    PYTHON,
    BenchError,
    Mqtt,
    Scope,
    check_abort,
    hardware_first,
    instrument_first,
    start_bridge,
    start_broker,
)
from benchmarks.line import FrameLog, PacedRelay
from benchmarks.ptyhop import PtyHop
from benchmarks.report import ItemResult, Table, Verdict, percentile
from benchmarks.rig import EmuHost, open_line
from tests.support import BridgeProcess
from tests.support.mosquitto import free_port
from tests.support.process import bridge_config
from tests.support.waiting import wait_until

GOAL_MS = 10.0
MEASURED = 6  # measured Rotor-EZ taking turns (a stop every ~0.3 s; one rotor's cycle is ~2 s)
EMU = {"speed_deg_s": 45.0, "brake_delay_s": 0.5, "jitter_deg": 0, "start_az_deg": 10}
BRIDGE = {"brake_delay_s": 0.5, "settle_s": 0.5, "idle_poll_interval_s": 0.5}
EMU_B = {**EMU, "brake_delay_s": 1.0}
BRIDGE_B = {**BRIDGE, "brake_delay_s": 1.0}
STOP_FRAME = b";"
POLL_QUERY = b"AI1;"  # the Rotor-EZ's bearing query (bridge/protocols/rotorez.py): 8.3 ms
JITTER_S = 0.2  # after "moving": one moving poll's period
LOAD_SETTLE_S = 1.0  # a load runs this long before its stops
BACKLOG = 60_000
HOLD_S = 15.0  # the round alone: the targets before its STOP keep arriving this long after it
MAX_BACKLOG = 400_000
TAIL_S = 10.0  # a round's rotor is watched this long after the round was read
TCP_CLIENTS, TCP_QUERY_CLIENTS = 16, 4
UDP_RATE = 20_000.0
PAGES, POSTERS = 10, 8
TRACKERS = 8
TIMELINE_EVENTS = 200_000  # per measured line, in the focused mode (a few minutes of polls)
TRACE_OVER_MS, TRACE_BEFORE_S = 9.0, 0.05  # the focused mode's line windows
TRACE_SLOWEST = 5  # and the slowest stops of each load, whatever their time
# the line hands its bytes to the controller directly (line.py rule 5); STOP_VIA_PTY=1 sends
# them through the controller's pty as before, to see what that hop adds on this machine
DIRECT = not os.environ.get("STOP_VIA_PTY")
# the loaded bridge's threads at a lower priority, its stop express not (module docstring)
BRIDGE_NICE = int(os.environ.get("BRIDGE_NICE") or 0)
# this tree's bridges with or without the stop express (module docstring)
EXPRESS_OFF = {"stop_express": False} if os.environ.get("STOP_EXPRESS") == "0" else None
# the focused mode of one load (module docstring): the control and that load alone
ONLY = os.environ.get("STOP_ONLY")
# the instrument's threads in the real-time class (module docstring; harness.py rule 6)
INSTRUMENT_RT = os.environ.get("STOP_INSTRUMENT_RT") != "0"
TRACK_GAP_S = 0.6  # between two rounds of 8 starts: one event at a time
STATION = (52.52, 13.29)
OLD_COMMIT = "9104bbc"
OLD_ENGINE, NEW_ENGINE = f"engine-{OLD_COMMIT}", "this-engine"
PAIR_ROTORS = 5  # per engine
CONTROL = "no load (control)"
BACKLOG_LOAD = "60,000-target backlog"
TRACKING_LOAD = "8 satellite trackings starting"


# == the loads' processes ========================================================================
# `python -m benchmarks.stop_under_load --load KIND JSON`: prints "started ..." once the load
# runs, answers commands on stdin, and at the end of its input prints "done <JSON counts>".


def _say(text: str) -> None:
    print(text, flush=True)


def _stdin_closed(timeout_s: float) -> bool:
    """Whether our input ended (waiting up to ``timeout_s`` for it to say something)."""
    ready, _, _ = select.select([sys.stdin], [], [], max(timeout_s, 0.0))
    return bool(ready) and not sys.stdin.readline()


def _paho(port: int, name: str) -> Any:
    import paho.mqtt.client as paho
    from paho.mqtt.enums import CallbackAPIVersion

    c = paho.Client(CallbackAPIVersion.VERSION2, client_id=f"{name}-{os.getpid()}")
    c.max_queued_messages_set(0)
    nodelay = (socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    c.on_socket_open = lambda _c, _u, s: s.setsockopt(*nodelay)  # type: ignore[attr-defined]
    c.connect("127.0.0.1", port, keepalive=60)
    c.loop_start()
    return c


def backlog_main(args: dict[str, Any]) -> None:
    """Per ``round TARGET STOP MARKER PAYLOAD COUNT`` line: COUNT targets (QoS 0) on TARGET, all
    written, then STOP (QoS 1) on STOP and PAYLOAD (QoS 1) on MARKER, on this one connection;
    says ``sent T_FIRST T_STOP`` (time.monotonic)."""
    c = _paho(args["port"], "backlog")
    rng = random.Random(11)
    payloads = [str(rng.randrange(0, 360)) for _ in range(997)]
    _say("started")
    rounds = 0
    for line in sys.stdin:
        words = line.split()
        if not words or words[0] != "round":
            continue
        target, stop, marker, payload, count = words[1:6]
        t_first = time.monotonic()
        info = None
        for i in range(int(count)):
            info = c.publish(target, payloads[i % len(payloads)], qos=0)
        if info is not None:
            info.wait_for_publish(300)  # every target written before the STOP is
        t_stop = time.monotonic()
        c.publish(stop, "STOP", qos=1)
        c.publish(marker, payload, qos=1)
        rounds += 1
        _say(f"sent {t_first:.6f} {t_stop:.6f}")
    c.loop_stop()
    _say("done " + json.dumps({"rounds": rounds}))


def tcp_main(args: dict[str, Any]) -> None:
    """``clients`` connections to a TCP front end, ``queries`` of them asking its position as
    fast as it reads, the others streaming bytes with no line end; a closed one reconnects."""
    query = {"rotctld": b"p\n", "gs232": b"C2\r", "easycomm": b"AZ EL\n"}[args["proto"]] * 64
    junk = b"Z" * 4096
    address = ("127.0.0.1", args["port"])
    counts = {"sent_bytes": 0, "received_bytes": 0, "reconnects": 0, "refused": 0}
    socks: dict[socket.socket, bytes] = {}

    def connect(payload: bytes) -> None:
        while True:
            try:
                s = socket.create_connection(address, timeout=5)
            except OSError:
                counts["refused"] += 1
                if _stdin_closed(0.1):
                    raise SystemExit(0) from None
                continue
            s.setblocking(False)
            socks[s] = payload
            return

    for i in range(args["clients"]):
        connect(query if i < args["queries"] else junk)
    _say("started")
    while True:
        ready, writable, _ = select.select([sys.stdin, *socks], list(socks), [], 0.5)
        if sys.stdin in ready and not sys.stdin.readline():
            break
        for s in writable:
            if s not in socks:
                continue
            try:
                counts["sent_bytes"] += s.send(socks[s])
            except BlockingIOError:
                pass
            except OSError:
                payload = socks.pop(s)
                s.close()
                counts["reconnects"] += 1
                connect(payload)
        for r in ready:
            if r is sys.stdin or r not in socks:
                continue
            s = r
            try:
                data = s.recv(65536)
            except BlockingIOError:
                continue
            except OSError:
                data = b""
            counts["received_bytes"] += len(data)
            if not data:
                payload = socks.pop(s)
                s.close()
                counts["reconnects"] += 1
                connect(payload)
    for s in socks:
        s.close()
    _say("done " + json.dumps(counts))


def udp_main(args: dict[str, Any]) -> None:
    """Datagrams at ``rate`` a second in all: the loggers' junk to the PST and N1MM ports,
    WSJT-X Status/Heartbeat from new instance names and junk to the WSJT-X port."""
    from benchmarks.logger_flood import junk
    from tests.support.wsjtx import StatusFields, heartbeat, status

    rng = random.Random(5)
    grids = ["JO62", "FN31pr", "PM95", "QF56", "IO91", "JN18", "KP20"]
    datagrams: list[tuple[int, bytes]] = []
    for i in range(3000):
        if i % 3 < 2:
            kind, data = junk(rng)
            datagrams.append((args["pst"] if kind == "pst" else args["n1mm"], data))
        else:
            instance = f"WSJT-X-{rng.randrange(10**9)}"
            form = rng.random()
            if form < 0.6:
                f = StatusFields(instance=instance, dx_call=f"DL{i}AB", dx_grid=rng.choice(grids))
                data = status(f)
            elif form < 0.8:
                data = heartbeat(instance)
            else:
                data = rng.randbytes(rng.randint(1, 300))
            datagrams.append((args["wsjtx"], data))
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sent = errors = 0
    _say("started")
    t0 = time.monotonic()
    while True:
        for _ in range(100):
            port, data = datagrams[sent % len(datagrams)]
            try:
                sock.sendto(data, ("127.0.0.1", port))
            except OSError:
                errors += 1
            sent += 1
        if _stdin_closed(t0 + sent / args["rate"] - time.monotonic()):
            break
    seconds = time.monotonic() - t0
    _say(
        "done " + json.dumps({"datagrams": sent, "per_s": round(sent / seconds), "errors": errors})
    )


async def _console(args: dict[str, Any]) -> dict[str, Any]:
    import aiohttp

    base = f"http://127.0.0.1:{args['port']}"
    origin = {"Origin": base}
    counts: dict[str, int] = {"page_loads": 0, "feed_messages": 0}
    done = asyncio.Event()
    loop = asyncio.get_running_loop()
    loop.add_reader(sys.stdin, lambda: None if sys.stdin.readline() else done.set())
    rng = random.Random(3)

    def count(key: str) -> None:
        counts[key] = counts.get(key, 0) + 1

    async def token(http: Any) -> str:
        async with http.post(f"{base}/api/session", json={}, headers=origin) as r:
            return str((await r.json())["token"])

    async def page(http: Any) -> None:
        while not done.is_set():
            try:
                for path in ("/", "/api/hello"):
                    async with http.get(base + path) as r:
                        await r.read()
                tok = await token(http)
                for path in ("/api/config", "/api/land"):
                    async with http.get(base + path, headers={"X-Rotor-Token": tok}) as r:
                        await r.read()
                counts["page_loads"] += 1
                async with http.ws_connect(f"{base}/api/live", headers=origin) as ws:
                    await ws.send_str(json.dumps({"token": tok}))
                    async for _ in ws:
                        counts["feed_messages"] += 1
                        if done.is_set():
                            break
            except (aiohttp.ClientError, OSError, KeyError, ValueError):
                count("page_errors")
                await asyncio.sleep(0.2)

    async def poster(http: Any) -> None:
        tok = ""
        while not done.is_set():
            try:
                if not tok:
                    tok = await token(http)
                rid = rng.choice(args["rotators"])
                headers = {**origin, "X-Rotor-Token": tok, "Content-Type": "application/json"}
                form = rng.random()
                if form < 0.5:
                    body = json.dumps({"command": "target", "az": rng.randrange(0, 360)})
                elif form < 0.7:
                    body = '{"command": "target", "az": '  # not JSON
                elif form < 0.85:
                    body = json.dumps({"command": "target", "azimuth": 10})  # an unknown key
                else:
                    body = json.dumps({"command": "park"})
                    headers.pop("X-Rotor-Token")  # no token
                url = f"{base}/api/rotators/{rid}/command"
                async with http.post(url, data=body, headers=headers) as r:
                    await r.read()
                    count(f"answered_{r.status}")
                    if r.status == 401:
                        tok = ""
            except (aiohttp.ClientError, OSError, KeyError, ValueError):
                count("post_errors")
                await asyncio.sleep(0.05)

    async with aiohttp.ClientSession(connector=aiohttp.TCPConnector(limit=0)) as http:
        tasks = [asyncio.create_task(page(http)) for _ in range(args["pages"])]
        tasks += [asyncio.create_task(poster(http)) for _ in range(args["posters"])]
        _say("started")
        await done.wait()
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
    return counts


def console_main(args: dict[str, Any]) -> None:
    counts = asyncio.run(_console(args))
    _say("done " + json.dumps(counts))


def _spot_block() -> bytes:
    """Spots a node sends, with the hostile lines among them."""
    rng = random.Random(9)
    prefixes = ["JA1", "VK2", "W1", "K3", "G4", "F5", "JR6", "N2"]
    lines: list[bytes] = []
    for i in range(96):
        call = f"{rng.choice(prefixes)}{chr(65 + i % 26)}{chr(65 + i // 26 % 26)}X"
        khz = rng.choice([7012.5, 14025.0, 14074.0, 21074.0, 28074.0, 50313.0])
        comment = rng.choice(["CQ", "FT8 -12 dB", "up 2", "599 TNX QSO", ""])
        hhmm = f"{i % 24:02d}{i % 60:02d}"
        lines.append(f"DX de EA5WU:   {khz:>8.1f}  {call:<12} {comment:<30} {hhmm}Z\r\n".encode())
    hostile = [
        b"DX de K1ABC: 1 JA1" + b" " * 490 + b"x\r\n",  # spaces and no time: a regex's worst
        b"DX de W3LPL-#:  " + b"9" * 3000 + b"\r\n",  # over the line limit
        b"\xff\xfb\x01\xff\xfd\x03 telnet options \xfe\x00\r\n",
        b"DX de " + bytes(range(1, 32)) * 8 + b"\r\n",
        b"DX de G4ABC: 14025.0 JA1ABC " + "\u00e9".encode("latin-1") * 200 + b" 1200Z\r\n",
    ]
    for i, bad in enumerate(hostile):
        lines.insert(i * 19 + 3, bad)
    return b"".join(lines)


def dxnode_main(args: dict[str, Any]) -> None:
    """A cluster node on loopback: asks every client its call, then is quiet until ``flood``
    (blocks of spots with hostile lines, as fast as the client reads) and ``quiet`` (answered
    with the counts of that flood)."""
    server = socket.create_server(("127.0.0.1", 0))
    block = _spot_block()
    lines_per_block = block.count(b"\n")
    flooding = threading.Event()
    counts = {"connections": 0, "bytes": 0}
    lock = threading.Lock()

    def session(conn: socket.socket) -> None:
        with contextlib.suppress(OSError), conn:
            conn.sendall(b"Hello, this is the benchmark's node\r\nlogin: ")
            conn.settimeout(60)
            got = b""
            while b"\n" not in got:
                data = conn.recv(256)
                if not data:
                    return
                got += data
            conn.setblocking(False)
            view = memoryview(b"")
            while True:
                if not flooding.wait(0.2):
                    continue
                if not view:
                    view = memoryview(block)
                _, writable, _ = select.select([], [conn], [], 0.2)
                if writable:
                    with contextlib.suppress(BlockingIOError):
                        n = conn.send(view[:65536])
                        view = view[n:]
                        with lock:
                            counts["bytes"] += n

    def accept() -> None:
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            counts["connections"] += 1
            threading.Thread(target=session, args=(conn,), daemon=True).start()

    threading.Thread(target=accept, daemon=True).start()
    _say(f"started {server.getsockname()[1]}")
    t0 = time.monotonic()
    for line in sys.stdin:
        word = line.strip()
        if word == "flood":
            with lock:
                counts["bytes"] = 0
            t0 = time.monotonic()
            flooding.set()
            _say("ok")
        elif word == "quiet":
            flooding.clear()
            seconds = time.monotonic() - t0
            with lock:
                lines = counts["bytes"] * lines_per_block // len(block)
            _say(f"quiet {json.dumps({'lines': lines, 'per_s': round(lines / seconds)})}")
    server.close()
    _say("done " + json.dumps({"connections": counts["connections"]}))


LOADERS: dict[str, Callable[[dict[str, Any]], None]] = {
    "backlog": backlog_main,
    "tcp": tcp_main,
    "udp": udp_main,
    "console": console_main,
    "dxnode": dxnode_main,
}


class Loader:
    """A load's process (above), started through the scope (harness rule 1)."""

    def __init__(self, scope: Scope, kind: str, args: dict[str, Any], name: str) -> None:
        self.name = name
        self.log = scope.workdir / f"load-{name}.log"
        argv = [PYTHON, "-m", "benchmarks.stop_under_load", "--load", kind, json.dumps(args)]
        self.proc = scope.spawn(
            argv, log_name=self.log.name, stdin=subprocess.PIPE, stdout=subprocess.PIPE
        )
        self.started = self.expect("started", 60)

    def read(self, timeout_s: float) -> str | None:
        assert self.proc.stdout is not None
        ready, _, _ = select.select([self.proc.stdout], [], [], max(timeout_s, 0.0))
        if not ready:
            return None
        return self.proc.stdout.readline().decode().strip()

    def expect(self, word: str, timeout_s: float) -> str:
        text = self.read(timeout_s)
        if text is None or not text.startswith(word):
            tail = self.log.read_text(errors="replace")[-1500:] if self.log.exists() else ""
            raise BenchError(f"load {self.name}: expected {word!r}, got {text!r}\n{tail}")
        return text[len(word) :].strip()

    def send(self, text: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(text.encode() + b"\n")
        self.proc.stdin.flush()

    def finish(self, timeout_s: float = 30.0) -> dict[str, Any]:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        counts: dict[str, Any] = json.loads(self.expect("done", timeout_s))
        return counts


# == the stops ===================================================================================
@dataclass
class Rotor:
    """A measured Rotor-EZ: its emulator, frames, topic, the client its STOP comes from."""

    rid: str
    engine: str
    emu: Any
    frames: FrameLog
    topic: str
    recorder: Mqtt
    sender: Mqtt
    by_target: bool = False  # turned by R/target (the pairs) or from the front panel
    line: PacedRelay | None = None  # its paced line: what it carried at a publish (line.py 7)
    step: str = "ready"
    t_turn: float = 0.0
    fire_at: float = 0.0
    stopped_at: float = 0.0
    retired: bool = False

    def state_since(self, t: float) -> str | None:
        m = self.recorder.last(f"{self.topic}/state")
        return m.text if m is not None and m.t >= t else None


@dataclass
class Sample:
    rid: str
    engine: str
    latency_s: float
    t: float
    t_sent: float = 0.0  # our publish returned (the STOP is in the kernel's socket)
    t_seen: float = 0.0  # this thread woke up to the stop frame
    wire_ahead_s: float = 0.0  # the line busy this long after the publish with earlier bytes
    ahead: bytes = b""  # those bytes' reads, whole (b"": the line was idle)
    after: bytes = b""  # what the line read from the publish to the stop frame
    # the broker handed the STOP to its first subscriber this long after the publish (the
    # delivery probe's kernel stamp); None: no probe, or it missed this stop
    broker_s: float | None = None
    # the controller stamped the stop frame this long after the line delivered its byte: the
    # instrument's own wait (line.py rule 8), inside latency_s; None: no paced line
    stamp_late_s: float | None = None
    # the line busy this long after the broker's hand-over with bytes it read before it, and
    # those bytes' reads (the docstring's floor; 0.0 and b"" when the probe missed the stop)
    handed_ahead_s: float = 0.0
    handed_ahead: bytes = b""
    after_hand_over: bytes = b""  # what the line read from the hand-over to the stop frame

    @property
    def floor_s(self) -> float:
        """What the stop waited for that was not the bridge's (the docstring): the broker not
        yet handing it over, then the line still busy with bytes the bridge wrote before it
        could know of the stop; a stop the probe missed keeps the line's wait at the publish."""
        if self.broker_s is None:
            return self.wire_ahead_s
        return max(self.wire_ahead_s, self.broker_s + self.handed_ahead_s)

    @property
    def floor_by(self) -> str:
        """Whose wait ended last, the floor's: "line" (still busy with the bridge's earlier
        bytes after the hand-over), "broker", or "" (neither held it up)."""
        if self.broker_s is None:
            return "line" if self.wire_ahead_s > 0 else ""
        if self.handed_ahead_s > 0:
            return "line"
        return "broker" if self.broker_s > 0 else ""

    @property
    def bytes_ahead(self) -> bytes:
        """The bridge's bytes the stop found on the line where its floor is judged: at the
        broker's hand-over, or at the publish when the probe missed it."""
        return self.ahead if self.broker_s is None else self.handed_ahead

    @property
    def bridge_s(self) -> float:
        """The latency beyond the stop's floor: what the bridge adds (the docstring)."""
        return self.latency_s - self.floor_s


class StopTaker:
    """The rotors take turns (module docstring): one ``step`` turns whoever is ready, arms who
    turns, and stops the first armed one whose moment has come."""

    def __init__(
        self,
        rotors: list[Rotor],
        rng: random.Random,
        check: Callable[[], None],
        probe: DeliveryProbe | None = None,
    ) -> None:
        self.rotors = rotors
        self.rng = rng
        self.check = check  # raises if the bridge(s) died
        self.missed = 0  # armed rotors that reached the far end before their stop
        self.probe = probe  # the broker's delivery of each STOP (the docstring)
        self.stops = 0  # measured STOPs published: each one's payload is its own with a probe

    def _advance(self, r: Rotor, now: float) -> None:
        if r.step == "ready" and not r.retired:
            m = r.recorder.last(f"{r.topic}/state")
            if m is None or m.text != "idle":
                return
            if m.t < r.stopped_at and now - r.stopped_at < 3.0:  # not yet said after our stop
                return  # (a rotor that ran to its far end was said idle before we saw it)
            st = r.emu.state()
            if st.is_moving:
                return
            far = 350 if st.az_deg < 180 else 10
            r.t_turn = now
            if r.by_target:
                r.sender.publish(f"{r.topic}/target", str(far))
            else:
                r.emu.manual_rotate(float(far))
            r.step = "turning"
        elif r.step == "turning":
            if r.state_since(r.t_turn) == "moving" and r.emu.state().is_moving:
                r.step = "armed"
                r.fire_at = now + self.rng.uniform(0.0, JITTER_S)
            elif now - r.t_turn > 1.0 and not r.emu.state().is_moving:
                self.missed += 1  # at the far end before the bridge said it turned (a load)
                r.step, r.stopped_at = "ready", now
            elif now - r.t_turn > 60.0:
                self.check()
                raise BenchError(f"{r.engine} {r.rid}: not seen turning 60 s after it was turned")

    def _stop(self, r: Rotor, before: Callable[[], None] | None) -> Sample | None:
        if before is not None:
            before()
            time.sleep(self.rng.uniform(0.0, 0.05))
        if not r.emu.state().is_moving:  # reached the far end first
            self.missed += 1
            r.step, r.stopped_at = "ready", time.monotonic()
            return None
        mark = r.frames.mark()
        self.stops += 1
        # any payload on R/stop is a stop (bridge/interfaces/mqtt/service.py rule 2): a number
        # of its own tells the probe's delivery of this STOP from every other
        payload = "STOP" if self.probe is None else f"STOP {self.stops}"
        topic = f"{r.topic}/stop"
        t0 = time.monotonic()
        r.sender.publish(topic, payload)
        t_sent = time.monotonic()
        frame = r.frames.wait(lambda f: f.data == STOP_FRAME, mark, 20.0)
        if frame is None:
            self.check()
            raise BenchError(f"{r.engine} {r.rid}: the stop never reached the controller")
        t_seen = time.monotonic()
        r.step, r.stopped_at = "ready", float(frame.time_s)
        line = r.line
        ahead = line.ahead_of(t0) if line is not None else None
        delivered = None if self.probe is None else self.probe.delivered(topic, payload.encode())
        late = None if line is None else line.stamp_late(float(frame.time_s), STOP_FRAME)
        handed = None if line is None or delivered is None else line.ahead_of(delivered)
        return Sample(
            r.rid,
            r.engine,
            float(frame.time_s) - t0,
            t0,
            t_sent,
            t_seen,
            0.0 if ahead is None else ahead.s,
            b"" if ahead is None else ahead.data,
            b"" if line is None else line.read_between(t0, float(frame.time_s)),
            None if delivered is None else delivered - t0,
            late,
            0.0 if handed is None else handed.s,
            b"" if handed is None else handed.data,
            b""
            if line is None or delivered is None
            else line.read_between(delivered, float(frame.time_s)),
        )

    def step(self, before: Callable[[], None] | None = None) -> Sample | None:
        check_abort()
        now = time.monotonic()
        for r in self.rotors:
            self._advance(r, now)
        armed = [r for r in self.rotors if r.step == "armed" and r.fire_at <= now]
        if not armed:
            time.sleep(0.003)
            return None
        return self._stop(min(armed, key=lambda r: r.fire_at), before)

    def take(
        self, n: int, before: Callable[[], None] | None = None, timeout_s: float = 600.0
    ) -> list[Sample]:
        out: list[Sample] = []
        deadline = time.monotonic() + timeout_s
        while len(out) < n:
            if time.monotonic() > deadline:
                raise BenchError(f"only {len(out)} of {n} stops in {timeout_s:g} s")
            sample = self.step(before)
            if sample is not None:
                out.append(sample)
        return out

    def settle(self, timeout_s: float = 30.0) -> None:
        """Every rotor still and said idle (no stop of the last phase left half done)."""
        deadline = time.monotonic() + timeout_s
        for r in self.rotors:
            if r.step == "armed":  # turned, never stopped: stop it (not measured)
                r.sender.publish(f"{r.topic}/stop", "STOP")
                r.step, r.stopped_at = "ready", time.monotonic()
            elif r.step == "turning":
                r.emu.manual_rotate(r.emu.state().az_deg)  # the panel lets go
                r.step, r.stopped_at = "ready", time.monotonic()
        while not all(
            r.state_since(0) == "idle" and not r.emu.state().is_moving for r in self.rotors
        ):
            if time.monotonic() > deadline:
                raise BenchError("the measured rotors did not come to rest between loads")
            time.sleep(0.05)


# == the loaded bridge ===========================================================================
@dataclass
class Loaded:
    scope: Scope
    broker_port: int
    bridge: BridgeProcess
    recorder: Mqtt
    sender: Mqtt
    loads_client: Mqtt
    taker: StopTaker
    b: Rotor
    d_frames: FrameLog
    ports: dict[str, int]
    node: Loader
    tle_names: list[str]
    timelines: dict[str, deque[tuple[Any, ...]]]  # the measured lines' relays (STOP_TRACE only)
    hop: PtyHop  # the host's own pty hop, beside the stops (benchmarks/ptyhop.py)
    probe: DeliveryProbe  # the broker's delivery of each STOP (benchmarks/delivery.py)
    instrument_rt: bool = False  # the instrument's threads in the real-time class (docstring)


def _tle(path: Path) -> list[str]:
    from benchmarks.sky_stops import tle_file

    return tle_file(path, time.time())


def start_loaded(scope: Scope, rng: random.Random) -> Loaded:
    from tests.dxcluster.cty_sample import CTY_DAT
    from tests.support.console import web_section
    from tests.support.ports import free_udp_port

    hop = PtyHop(scope)  # hardware's priority, as the controllers (harness rule 5)
    broker_port = start_broker(scope, "max_queued_messages 0\n")  # the whole backlog delivered
    # subscribed before the bridge to the same exact topics: served first (delivery.py rule 2)
    probe = DeliveryProbe(broker_port, [f"rotor/m{i}/stop" for i in range(MEASURED)])
    scope.callback(probe.close)
    node = Loader(scope, "dxnode", {}, "dxnode")
    ports = {
        "rotctld": free_port(),
        "gs232": free_port(),
        "easycomm": free_port(),
        "pst": free_udp_port(),
        "n1mm": free_udp_port(),
        "wsjtx": free_udp_port(),
        "web": free_port(),
        "node": int(node.started),
    }
    lines: dict[str, tuple[Any, FrameLog, PacedRelay | None]] = {}
    settings: list[dict[str, Any]] = []
    timelines: dict[str, deque[tuple[Any, ...]]] = {}
    traced = bool(os.environ.get("STOP_TRACE"))  # keep the relays' timelines (line.py rule 6)
    for i in range(MEASURED):
        frames = FrameLog(sched=traced)
        timeline = timelines[f"m{i}"] = deque(maxlen=TIMELINE_EVENTS) if traced else None
        emu, relay, path = open_line(
            scope, "rotorez", frames, EMU, name=f"tty-m{i}", timeline=timeline, direct=DIRECT
        )
        lines[f"m{i}"] = (emu, frames, relay)
        settings.append({"id": f"m{i}", "model": "rotorez", "port": str(path), **BRIDGE})
    settings[0].update(
        rotctld_port=ports["rotctld"],
        gs232_port=ports["gs232"],
        easycomm_port=ports["easycomm"],
        pst_udp_port=ports["pst"],
        n1mm_rotor_name="Yagi",
        n1mm_udp_port=ports["n1mm"],
    )
    b_frames, d_frames = FrameLog(), FrameLog()
    b_emu, _r, b_path = open_line(scope, "rotorez", b_frames, EMU_B, name="tty-b", direct=DIRECT)
    _d_emu, _r, d_path = open_line(scope, "rotorez", d_frames, EMU, name="tty-d", direct=DIRECT)
    settings.append({"id": "b", "model": "rotorez", "port": str(b_path), **BRIDGE_B})
    settings.append({"id": "d", "model": "rotorez", "port": str(d_path), **BRIDGE})
    host = EmuHost(scope, "md01", TRACKERS)
    settings += [
        {"id": f"t{i}", "model": "md01", "port": str(host.link(i))} for i in range(TRACKERS)
    ]
    cty = scope.workdir / "cty.dat"
    cty.write_text(CTY_DAT)
    tle_names = _tle(scope.workdir / "sats.tle")
    sections = {
        "station": {"latitude_deg": STATION[0], "longitude_deg": STATION[1]},
        "tracking": {"tle_file": str(scope.workdir / "sats.tle")},
        "web": web_section(ports["web"]),
        "wsjtx": {"enabled": True, "port": ports["wsjtx"], "bind": "127.0.0.1"},
        "dxcluster": {
            "enabled": True,
            "host": "127.0.0.1",
            "port": ports["node"],
            "login": "G4ABC",
            "cty_file": str(cty),
        },
    }
    bridge = start_bridge(
        scope, broker_port, settings, homeassistant=False, sections=sections, mqtt=EXPRESS_OFF
    )
    recorder = Mqtt(broker_port, ["rotor/+/state", "rotor/+/availability"], name="sul-rec")
    scope.callback(recorder.close)
    sender = Mqtt(broker_port, [], name="sul-stop")
    scope.callback(sender.close)
    loads_client = Mqtt(broker_port, [], name="sul-loads")
    scope.callback(loads_client.close)
    rt = INSTRUMENT_RT and instrument_first()  # every thread of ours is up (harness rule 6)
    try:
        recorder.wait_all([f"rotor/{s['id']}/availability" for s in settings], "online", 90)
        recorder.wait_all([f"rotor/m{i}/state" for i in range(MEASURED)], "idle", 60)
    except BenchError:
        bridge.check()
        raise
    if BRIDGE_NICE:
        _renice(bridge)
    rotors = [
        Rotor(rid, "now", emu, frames, f"rotor/{rid}", recorder, sender, line=relay)
        for rid, (emu, frames, relay) in lines.items()
    ]
    taker = StopTaker(rotors, rng, bridge.check, probe)
    b = Rotor("b", "now", b_emu, b_frames, "rotor/b", recorder, sender)
    return Loaded(
        scope,
        broker_port,
        bridge,
        recorder,
        sender,
        loads_client,
        taker,
        b,
        d_frames,
        ports,
        node,
        tle_names,
        timelines,
        hop,
        probe,
        rt,
    )


@dataclass
class PhaseResult:
    name: str
    samples: list[Sample]
    cpu_pct: float
    loadavg: float
    applied: str
    counts: dict[str, Any] = field(default_factory=dict)


def cpu_seconds(pid: int) -> float:
    """The process's CPU time, its ended threads' included (a TCP client's thread ends with
    its connection: the live threads' sum would go down)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _measure(
    lo: Loaded, name: str, n: int, take: Callable[[], list[Sample]]
) -> tuple[list[Sample], float, float]:
    pid = lo.bridge.pid
    c0, t0, la0 = cpu_seconds(pid), time.monotonic(), os.getloadavg()[0]
    samples = take()
    wall = time.monotonic() - t0
    cpu = 100.0 * (cpu_seconds(pid) - c0) / wall
    la = (la0 + os.getloadavg()[0]) / 2
    f = floor_split(samples)
    print(
        f"  {name}: {len(samples)} stops, p50 {f.p50_ms:.1f} p99 {f.p99_ms:.1f} "
        f"max {f.max_ms:.1f} ms, the broker's delivery p99 {f.broker_p99_ms:.1f} ms "
        f"({f.broker_missed} missed), {f.behind} behind bytes on the line ({f.queries} "
        f"queries), the bridge's part p99 {f.bridge_p99_ms:.1f} ms, {query_after(samples)} "
        f"behind a query written after the hand-over; bridge CPU {cpu:.0f} %, load {la:.1f}; "
        f"{wall:.0f} s",
        file=sys.stderr,
        flush=True,
    )
    lo.bridge.check()
    return samples, cpu, la


def queued_bytes(tcp_ports: list[int], udp_ports: list[int]) -> int:
    """Bytes still queued in the kernel on a connection to or from these TCP ports, or for
    these UDP ports (/proc/net): what a load sent that the bridge has not read yet."""
    total = 0
    for kind, ports in (("tcp", set(tcp_ports)), ("udp", set(udp_ports))):
        if not ports:
            continue
        with open(f"/proc/net/{kind}") as f:
            for line in f.readlines()[1:]:
                fields = line.split()
                local, remote = (int(a.rsplit(":", 1)[1], 16) for a in fields[1:3])
                if local in ports or remote in ports:
                    tx, rx = (int(v, 16) for v in fields[4].split(":"))
                    total += tx + rx
    return total


def wait_read(tcp_ports: list[int], udp_ports: list[int], timeout_s: float = 120.0) -> float:
    """Seconds until the bridge has read what a load left queued (the next load must not
    meet this one's leftovers); inf if it has not after ``timeout_s``."""
    t0 = time.monotonic()
    while queued_bytes(tcp_ports, udp_ports) > 0:
        check_abort()
        if time.monotonic() - t0 > timeout_s:  # said in the row (the next load meets it)
            return float("inf")
        time.sleep(0.05)
    return time.monotonic() - t0


def simple_phase(
    lo: Loaded,
    name: str,
    n: int,
    start: Callable[[], Any] | None,
    stop: Callable[[Any], tuple[str, dict[str, Any]]] | None,
    before: Callable[[], None] | None = None,
) -> PhaseResult:
    lo.taker.settle()
    load = start() if start is not None else None
    ABORT.wait(LOAD_SETTLE_S if start is not None else 0.0)
    samples, cpu, la = _measure(lo, name, n, lambda: lo.taker.take(n, before))
    applied, counts = stop(load) if stop is not None else ("nothing", {})
    return PhaseResult(name, samples, cpu, la, applied, counts)


def loader_phase(
    lo: Loaded,
    name: str,
    n: int,
    kind: str,
    args: dict[str, Any],
    tcp: list[int] = [],  # noqa: B006 (read only)
    udp: list[int] = [],  # noqa: B006
) -> PhaseResult:
    def start() -> Loader:
        return Loader(lo.scope, kind, args, name=kind + "-" + str(args.get("proto", "")))

    def stop(load: Loader) -> tuple[str, dict[str, Any]]:
        counts = load.finish()
        counts["read_after_s"] = round(wait_read(tcp, udp), 1)
        return describe(kind, counts), counts

    return simple_phase(lo, name, n, start, stop)


def describe(kind: str, c: dict[str, Any]) -> str:
    return _describe(kind, c) + f"; the rest read {c['read_after_s']:g} s after the load ended"


def _describe(kind: str, c: dict[str, Any]) -> str:
    if kind == "tcp":
        return (
            f"{c['sent_bytes'] / 1e6:.1f} MB sent, {c['received_bytes'] / 1e6:.2f} MB answered, "
            f"{c['reconnects']} reconnects"
        )
    if kind == "udp":
        return f"{c['datagrams']:,} datagrams ({c['per_s']:,}/s)"
    if kind == "console":
        posts = sum(v for k, v in c.items() if k.startswith("answered_"))
        codes = ", ".join(
            f"{k[9:]}: {v}" for k, v in sorted(c.items()) if k.startswith("answered_")
        )
        return (
            f"{c['page_loads']} page loads, {c['feed_messages']:,} feed messages, "
            f"{posts:,} POSTs answered ({codes})"
        )
    return json.dumps(c)


def dx_phase(lo: Loaded, name: str, n: int) -> PhaseResult:
    def start() -> None:
        lo.node.send("flood")
        lo.node.expect("ok", 10)

    def stop(_load: None) -> tuple[str, dict[str, Any]]:
        lo.node.send("quiet")
        counts: dict[str, Any] = json.loads(lo.node.expect("quiet", 10))
        counts["read_after_s"] = round(wait_read([lo.ports["node"]], []), 1)
        return (
            f"{counts['lines']:,} lines sent ({counts['per_s']:,}/s), 5 in 101 hostile; "
            f"the rest read {counts['read_after_s']:g} s after the node fell quiet"
        ), counts

    return simple_phase(lo, name, n, start, stop)


def tracking_phase(lo: Loaded, name: str, n: int) -> PhaseResult:
    from benchmarks.sky_stops import round_tle

    rounds = [0]
    last = [0.0]

    def before() -> None:
        time.sleep(max(0.0, last[0] + TRACK_GAP_S - time.monotonic()))  # one event at a time
        last[0] = time.monotonic()
        payload = round_tle(rounds[0])
        rounds[0] += 1
        for i in range(TRACKERS):
            lo.loads_client.publish(f"rotor/t{i}/track", payload)

    def stop(_load: None) -> tuple[str, dict[str, Any]]:
        for i in range(TRACKERS):
            lo.loads_client.publish(f"rotor/t{i}/track", "off")
        return f"{rounds[0]} rounds of {TRACKERS} R/track, new elements each", {"rounds": rounds[0]}

    return simple_phase(lo, name, n, lambda: None, stop, before)


# -- the backlog ----------------------------------------------------------------------------------
@dataclass
class Round:
    marker_az: int
    t_sent: float  # the loader asked
    count: int  # targets before its STOP
    t_first: float = 0.0
    t_stop: float = 0.0  # its STOP published (every target written before it)
    t_read: float | None = None  # d got the marker: the main connection read the round
    stop_latency_s: float | None = None
    starts_after: int = 0  # moves the controller executed after the stop frame
    moves_after: int = 0  # move frames written after it (executed or not)
    alone: bool = False  # no measured stop beside it
    stops_beside: int = 0


def alone_count(rounds: list[Round]) -> int:
    """Targets for the round alone: as many as keep this bridge reading for HOLD_S after the
    STOP, judging by the rounds before (publishing them goes on while the bridge reads), at
    least BACKLOG and at most MAX_BACKLOG: a fault that lets targets out after a timeout
    shorter than HOLD_S shows on a fast machine too."""
    read = [(r.count, r.t_stop - r.t_first, r.t_read - r.t_first) for r in rounds if r.t_read]
    if not read:
        return BACKLOG
    count = sum(c for c, _, _ in read)
    per_target_s = (sum(rd for _, _, rd in read) - sum(p for _, p, _ in read)) / count
    if per_target_s <= 0:
        return MAX_BACKLOG
    return int(min(MAX_BACKLOG, max(BACKLOG, HOLD_S / per_target_s)))


def backlog_phase(lo: Loaded, name: str, n: int) -> PhaseResult:
    """Rounds while the stops are taken, then one round alone: every measured stop is a halt
    of its own, with its own hold on the main connection, and must not stand in for the
    backlog's STOP being kept on its own."""
    lo.taker.settle()
    loader = Loader(lo.scope, "backlog", {"port": lo.broker_port}, "backlog")
    rounds: list[Round] = []
    samples: list[Sample] = []
    marks = {"b": 0, "d": 0}

    def close(r: Round) -> None:
        """Judge a round once TAIL_S has passed since it was read."""
        ABORT.wait(max(0.0, (r.t_read or 0.0) + TAIL_S - time.monotonic()))
        frames = lo.b.frames.since(marks["b"])
        stop = next((f for f in frames if f.data == STOP_FRAME and f.time_s >= r.t_stop), None)
        after = stop.time_s if stop is not None else r.t_stop
        r.stop_latency_s = None if stop is None else stop.time_s - r.t_stop
        moves = [f for f in frames if f.time_s > after and f.data[:3] in (b"AP1", b"AM1")]
        r.moves_after = len(moves)
        r.starts_after = sum(1 for f in moves if f.outcome == "executed")

    def begin(alone: bool, count: int = BACKLOG) -> Round:
        if rounds:
            close(rounds[-1])
        marks["b"], marks["d"] = lo.b.frames.mark(), lo.d_frames.mark()
        r = Round(100 if len(rounds) % 2 == 0 else 260, time.monotonic(), count, alone=alone)
        rounds.append(r)
        topics = "rotor/b/target rotor/b/stop rotor/d/target"
        loader.send(f"round {topics} {r.marker_az} {count}")
        return r

    def read(r: Round) -> bool:
        """Whether the main connection has read the round (its marker reached d)."""
        if not r.t_stop:
            text = loader.read(0)
            if text is not None:
                if not text.startswith("sent"):
                    raise BenchError(f"backlog loader: {text!r}")
                r.t_first, r.t_stop = map(float, text.split()[1:3])
        want = f"AP1{r.marker_az:03d}".encode()
        hit = next((f for f in lo.d_frames.since(marks["d"]) if f.data.startswith(want)), None)
        if hit is not None and r.t_stop:
            r.t_read = float(hit.time_s)
            return True
        if time.monotonic() - r.t_sent > 300:
            drops = (lo.scope.workdir / "mosquitto.log").read_text(errors="replace")
            raise BenchError(
                f"backlog: a round's end marker did not reach its rotor in 300 s (mosquitto "
                f"logged {drops.count('being dropped')} drop notice(s))"
            )
        return False

    def take() -> list[Sample]:
        while len(samples) < n:
            r = begin(alone=False)
            while not read(r):
                if len(samples) < n:
                    s = lo.taker.step()
                    r.stops_beside += s is not None
                    if s is not None:
                        samples.append(s)
                else:
                    time.sleep(0.01)
        return samples

    got, cpu, la = _measure(lo, name, n, take)
    lo.taker.settle()
    alone = begin(alone=True, count=alone_count(rounds))
    while not read(alone):
        check_abort()
        time.sleep(0.01)
    close(alone)
    loader.finish()
    lo.bridge.check()
    drops = (lo.scope.workdir / "mosquitto.log").read_text(errors="replace").count("dropped")
    counts = {
        "rounds": [
            {
                "alone": r.alone,
                "targets": r.count,
                "stops_beside": r.stops_beside,
                "publish_s": round(r.t_stop - r.t_first, 2),
                "read_s": None if r.t_read is None else round(r.t_read - r.t_first, 2),
                "held_s": None if r.t_read is None else round(r.t_read - r.t_stop, 2),
                "stop_ms": None if r.stop_latency_s is None else round(r.stop_latency_s * 1000, 2),
                "starts_after_stop": r.starts_after,
                "move_frames_after_stop": r.moves_after,
            }
            for r in rounds
        ],
        "broker_drop_notices": drops,
    }
    beside = [r for r in rounds if not r.alone]
    read_s = ", ".join(f"{r.t_read - r.t_first:.0f}" for r in beside if r.t_read is not None)
    applied = f"{len(beside)} round(s) of {BACKLOG:,} targets + STOP, read in {read_s} s"
    return PhaseResult(name, got, cpu, la, applied, counts)


def _renice(bridge: BridgeProcess) -> None:
    """BRIDGE_NICE: every thread of the bridge's process (a nice value is a thread's on
    Linux), after its stop express started (a child inherits its parent thread's value)."""
    if EXPRESS_OFF is None:
        wait_until(
            lambda: "stop express up" in bridge.log(),
            30,
            "the stop express up",
            error=BenchError,
        )
    for tid in os.listdir(f"/proc/{bridge.pid}/task"):
        os.setpriority(os.PRIO_PROCESS, int(tid), BRIDGE_NICE)


# == the engine of 2026-11-26 against this one ===================================================
def start_engine(
    scope: Scope, engine: str, old_root: Path | None, rng: random.Random
) -> tuple[BridgeProcess, list[Rotor]]:
    broker_port = start_broker(scope)
    specs, lines = [], []
    for i in range(PAIR_ROTORS):
        frames = FrameLog()
        emu, relay, path = open_line(
            scope, "rotorez", frames, EMU, name=f"tty-{engine}{i}", direct=DIRECT
        )
        lines.append((f"p{i}", emu, frames, relay))
        specs.append({"id": f"p{i}", "model": "rotorez", "port": str(path), **BRIDGE})
    config = bridge_config(
        scope.workdir,
        broker_port,
        specs,
        client_id=f"bench-{engine}-{os.getpid()}",
        sections={"homeassistant": {"enabled": False}},
        mqtt=EXPRESS_OFF if old_root is None else None,
        state_name=f"{engine}-state.json",
    )
    if old_root is None:
        spawn = scope.spawner
    else:
        env = engine_env(old_root)

        def spawn(argv: list[str], log: Path) -> subprocess.Popen[bytes]:
            return scope.spawn(argv, log_name=log.name, cwd=old_root, env=env)

    bridge = BridgeProcess(
        scope.workdir, config, log_level="INFO", name=engine, spawn=spawn, error=BenchError
    ).start()
    recorder = Mqtt(broker_port, ["rotor/+/state", "rotor/+/availability"], name=f"rec-{engine}")
    scope.callback(recorder.close)
    sender = Mqtt(broker_port, [], name=f"send-{engine}")
    scope.callback(sender.close)
    try:
        recorder.wait_all([f"rotor/{s['id']}/availability" for s in specs], "online", 60)
        recorder.wait_all([f"rotor/{s['id']}/state" for s in specs], "idle", 60)
    except BenchError:
        bridge.check()
        raise
    rotors = [
        Rotor(rid, engine, emu, frames, f"rotor/{rid}", recorder, sender, True, line=relay)
        for rid, emu, frames, relay in lines
    ]
    return bridge, rotors


def pairs(scope: Scope, n: int, rng: random.Random) -> dict[str, Any]:
    """``n`` target+stop pairs on each engine, their rotors taking turns."""
    with Scope(scope.workdir / "pairs") as inner:
        old_root, why = engine_at(inner, OLD_COMMIT)
        if old_root is None:
            return {"error": why}
        bridges, rotors = {}, []
        try:
            for engine, root in ((OLD_ENGINE, old_root), (NEW_ENGINE, None)):
                sub = Scope(inner.workdir / engine)
                inner.enter_context(sub)
                bridges[engine], rs = start_engine(sub, engine, root, rng)
                rotors.append(rs)
        except BenchError as exc:
            if OLD_ENGINE not in bridges:
                return {"error": f"the engine of commit {OLD_COMMIT} did not run: {exc}"}
            raise
        mixed = [r for pair in zip(*rotors, strict=True) for r in pair]
        if INSTRUMENT_RT:
            instrument_first()  # the pairs' emulators, lines and clients too (harness rule 6)

        def check() -> None:
            for b in bridges.values():
                b.check()

        taker = StopTaker(mixed, rng, check)
        got: dict[str, list[float]] = {e: [] for e in bridges}
        own: dict[str, list[float]] = {e: [] for e in bridges}  # less the line's wait
        queries: dict[str, int] = {e: 0 for e in bridges}  # stops behind a poll query
        deadline = time.monotonic() + 1800
        while any(len(v) < n for v in got.values()):
            if time.monotonic() > deadline:
                raise BenchError(f"pairs: {[len(v) for v in got.values()]} of {n} in 1800 s")
            s = taker.step()
            if s is None:
                continue
            if len(got[s.engine]) < n:  # (a stop already armed may come after the n-th)
                got[s.engine].append(s.latency_s * 1000)
                own[s.engine].append((s.latency_s - s.wire_ahead_s) * 1000)
                queries[s.engine] += s.wire_ahead_s > 0 and behind_query(s.ahead)
            if len(got[s.engine]) >= n:
                for r in mixed:
                    r.retired = r.retired or r.engine == s.engine
        check()
        print(f"  pairs: {[len(v) for v in got.values()]}, missed {taker.missed}", file=sys.stderr)
        return {"engines": got, "own": own, "queries": queries}


# == the item ====================================================================================
def run(scope: Scope, quick: bool) -> ItemResult:
    result = ItemResult("stop_under_load", "Stops under every load, and against the old engine")
    # harness rule 5: the controllers and the stops' publisher before the bridge, broker, loads
    result.data["controllers_first"] = hardware_first()
    # this process is the instrument: its emulators and paced lines hand the interpreter lock
    # over as quickly as the bridge does (app.py), and no collection of its frame logs runs
    # between a stop frame and its time stamp
    switch = sys.getswitchinterval()
    sys.setswitchinterval(0.0005)
    gc.disable()
    try:
        return _run(scope, quick, result)
    finally:
        gc.enable()
        sys.setswitchinterval(switch)


def _run(scope: Scope, quick: bool, result: ItemResult) -> ItemResult:
    n = 20 if quick else 60
    n_pairs = 60 if quick else 300
    rng = random.Random(29)
    phases: list[PhaseResult] = []
    trace = os.environ.get("STOP_TRACE")  # the focused mode: module docstring's end
    focused = {
        "trackings": lambda lo: tracking_phase(lo, TRACKING_LOAD, n),
        "backlog": lambda lo: backlog_phase(lo, BACKLOG_LOAD, n),
        **{proto: (lambda lo, proto=proto: tcp_phase(lo, proto, n)) for proto in TCP_LABELS},
    }
    if ONLY is not None and ONLY not in focused:
        raise BenchError(f"STOP_ONLY={ONLY!r}: one of {', '.join(focused)}")
    with Scope(scope.workdir / "loaded") as inner:
        lo = start_loaded(inner, rng)
        result.data["instrument_rt"] = lo.instrument_rt
        ABORT.wait(2.0)  # past the start-up
        phases.append(simple_phase(lo, CONTROL, n, None, None))
        if ONLY is not None:
            phases.append(focused[ONLY](lo))
            return _focused_end(result, lo, phases, trace)
        phases.append(backlog_phase(lo, BACKLOG_LOAD, n))
        if trace is not None:
            return _traced(result, lo, phases, n, trace)
        for proto in TCP_LABELS:
            phases.append(tcp_phase(lo, proto, n))
        udp = {"pst": lo.ports["pst"], "n1mm": lo.ports["n1mm"], "wsjtx": lo.ports["wsjtx"]}
        label = "PST + N1MM + WSJT-X UDP floods"
        args = {**udp, "rate": UDP_RATE}
        phases.append(loader_phase(lo, label, n, "udp", args, udp=list(udp.values())))
        phases.append(dx_phase(lo, "DX cluster: hostile lines, full-speed spots", n))
        console = {
            "port": lo.ports["web"],
            "pages": PAGES,
            "posters": POSTERS,
            "rotators": [f"t{i}" for i in range(TRACKERS)],
        }
        label = "console: 10 pages + POST flood"
        phases.append(loader_phase(lo, label, n, "console", console, tcp=[lo.ports["web"]]))
        phases.append(tracking_phase(lo, TRACKING_LOAD, n))
        missed = lo.taker.missed
        lo.bridge.check()
        lo.hop.finish()
    report_loads(result, phases, missed, lo.hop, lo.probe)
    report_pairs(result, pairs(scope, n_pairs, rng), n_pairs)
    return result


TCP_LABELS = {"rotctld": "rotctld", "gs232": "GS-232", "easycomm": "Easycomm"}


def tcp_phase(lo: Loaded, proto: str, n: int) -> PhaseResult:
    """16 TCP clients on m0's port of ``proto`` (module docstring)."""
    args = {"clients": TCP_CLIENTS, "queries": TCP_QUERY_CLIENTS, "port": lo.ports[proto]}
    label = f"{TCP_LABELS[proto]}: 16 TCP clients"
    return loader_phase(lo, label, n, "tcp", {**args, "proto": proto}, tcp=[lo.ports[proto]])


def _traced(
    result: ItemResult, lo: Loaded, phases: list[PhaseResult], n: int, trace: str
) -> ItemResult:
    """STOP_TRACE=<file>: the control, the backlog, the console and the trackings only; the
    bridge writes its steps to <file> as it exits (benchmarks/stop_trace.py) and the stops go
    to <file>.samples.json: ``python -m benchmarks.stop_trace <file> <file>.samples.json``."""
    console = {
        "port": lo.ports["web"],
        "pages": PAGES,
        "posters": POSTERS,
        "rotators": [f"t{i}" for i in range(TRACKERS)],
    }
    label = "console: 10 pages + POST flood"
    phases.append(loader_phase(lo, label, n, "console", console, tcp=[lo.ports["web"]]))
    phases.append(tracking_phase(lo, TRACKING_LOAD, n))
    return _focused_end(result, lo, phases, trace)


def _focused_end(
    result: ItemResult, lo: Loaded, phases: list[PhaseResult], trace: str | None
) -> ItemResult:
    """The rows of a focused run (STOP_TRACE, STOP_ONLY), and with STOP_TRACE the stops and
    their lines' windows for ``python -m benchmarks.stop_trace``."""
    missed = lo.taker.missed
    lo.bridge.check()
    lo.hop.finish()
    if trace is not None:
        samples = {
            p.name: [
                (
                    *(s.rid, s.t, s.latency_s, s.t_sent, s.t_seen),
                    s.wire_ahead_s,
                    _text(s.ahead),
                    s.broker_s,
                    s.stamp_late_s,
                )
                for s in p.samples
            ]
            for p in phases
        }
        Path(trace + ".samples.json").write_text(json.dumps(samples))
        Path(trace + ".lines.json").write_text(json.dumps(_line_windows(lo, phases)))
    report_loads(result, phases, missed, lo.hop, lo.probe)
    return result


def _line_windows(lo: Loaded, phases: list[PhaseResult]) -> dict[str, Any]:
    """For each stop over TRACE_OVER_MS and the TRACE_SLOWEST of each load, what its line
    carried from TRACE_BEFORE_S before the publish to just after its stop frame: the relay's
    reads and deliveries (line.py rule 6) and the frames the controller logged
    (benchmarks/stop_trace.py prints them)."""
    out: dict[str, Any] = {}
    frames = {r.rid: r.frames for r in lo.taker.rotors}
    for p in phases:
        rows = []
        slowest = sorted(p.samples, key=lambda s: -s.latency_s)[:TRACE_SLOWEST]
        for s in p.samples:
            over = s.latency_s * 1000 > TRACE_OVER_MS or s in slowest
            if not over or s.rid not in lo.timelines:
                continue
            lo_t, hi_t = s.t - TRACE_BEFORE_S, s.t + s.latency_s + 0.005
            relay = [
                (kind, t, data.decode("latin-1"), due, *sched)
                for kind, t, data, due, *sched in list(lo.timelines[s.rid])
                if lo_t <= t <= hi_t
            ]
            log = frames[s.rid]
            stats = log.sched or []
            logged = [
                (f.time_s, f.data.decode("latin-1"), f.outcome, *(stats[i] if stats else ()))
                for i, f in enumerate(log.since(0))
                if lo_t <= f.time_s <= hi_t
            ]
            rows.append({"rid": s.rid, "t0": s.t, "relay": relay, "frames": logged})
        out[p.name] = rows
    return out


def _ms(samples: list[Sample]) -> list[float]:
    return [s.latency_s * 1000.0 for s in samples]


def _text(data: bytes) -> str:
    return data.decode("latin-1")


def behind_query(ahead: bytes) -> bool:
    """Whether what a stop found on its line was poll queries and nothing else."""
    n = len(ahead) // len(POLL_QUERY)
    return n > 0 and ahead == POLL_QUERY * n


@dataclass(frozen=True)
class FloorSplit:
    """A row's figures in ms (the docstring's floor): the raw latency, the broker's delivery,
    the bridge's part, and why the stops over the goal took that long."""

    p50_ms: float
    p99_ms: float
    max_ms: float
    broker_p99_ms: float  # over the stops the probe saw (nan: none)
    broker_missed: int  # stops the probe did not see: their floor is the line's alone
    bridge_p99_ms: float  # latency less the floor: what the goal judges
    behind: int  # stops that found bytes of the bridge's already on the line
    queries: int  # of those, poll queries and nothing else
    over: int  # stops over the goal, raw
    over_broker: int  # of those, the broker's delivery the floor and most of the time
    over_line: int  # of those, the line's bytes the floor and most of the time
    over_broker_max_ms: float  # the broker's latest delivery among the first (nan: none)
    over_line_max_ms: float  # the line's longest wait among the second (nan: none)


def _mostly(s: Sample) -> str:
    """What a stop waited for most: "broker" or "line" (its floor's), or "bridge" (its part)."""
    return "bridge" if s.bridge_s > s.floor_s else s.floor_by


def floor_split(samples: list[Sample]) -> FloorSplit:
    ms = sorted(_ms(samples))
    broker = [s.broker_s * 1000.0 for s in samples if s.broker_s is not None]
    behind = [s for s in samples if s.bytes_ahead]
    over = [s for s in samples if s.latency_s * 1000.0 > GOAL_MS]
    by_broker = [s.floor_s * 1000.0 for s in over if _mostly(s) == "broker"]
    by_line = [s.floor_s * 1000.0 for s in over if _mostly(s) == "line"]
    return FloorSplit(
        p50_ms=percentile(ms, 50),
        p99_ms=percentile(ms, 99),
        max_ms=ms[-1] if ms else math.nan,
        broker_p99_ms=percentile(broker, 99),
        broker_missed=len(samples) - len(broker),
        bridge_p99_ms=percentile([s.bridge_s * 1000.0 for s in samples], 99),
        behind=len(behind),
        queries=sum(behind_query(s.bytes_ahead) for s in behind),
        over=len(over),
        over_broker=len(by_broker),
        over_line=len(by_line),
        over_broker_max_ms=max(by_broker, default=math.nan),
        over_line_max_ms=max(by_line, default=math.nan),
    )


def _why_over(f: FloorSplit) -> str:
    """What the stops over the goal waited for."""
    why = []
    if f.over_broker:
        why.append(
            f"{f.over_broker} mostly for the broker's delivery (up to "
            f"{f.over_broker_max_ms:.1f} ms after the publish: mosquitto is one thread, still "
            "passing on what came before or waiting for a core)"
        )
    if f.over_line:
        why.append(
            f"{f.over_line} mostly for bytes of the bridge's already on the line (up to "
            f"{f.over_line_max_ms:.1f} ms: a UART does not give them back)"
        )
    own = f.over - f.over_broker - f.over_line
    if own:
        why.append(f"{own} mostly for the bridge itself")
    return f"of the {f.over} stop(s) over {GOAL_MS:g} ms, " + ", ".join(why)


def row_verdict(name: str, samples: list[Sample]) -> Verdict:
    """A load's verdict: the goal judges the bridge's part; the text says the raw p99 first,
    and when that misses the goal while the bridge's part meets it, says why."""
    f = floor_split(samples)
    met = f.bridge_p99_ms <= GOAL_MS
    if f.p99_ms <= GOAL_MS:
        head = (
            f"raw p99 {f.p99_ms:.1f} ms (publish -> ';'); the bridge's part p99 "
            f"{f.bridge_p99_ms:.1f} ms"
        )
    elif met:
        head = (
            f"the raw p99 {f.p99_ms:.1f} ms (publish -> ';') misses {GOAL_MS:g} ms while the "
            f"bridge's part meets it (p99 {f.bridge_p99_ms:.1f} ms): {_why_over(f)}"
        )
    else:
        head = (
            f"the bridge's part p99 {f.bridge_p99_ms:.1f} ms misses {GOAL_MS:g} ms; raw p99 "
            f"{f.p99_ms:.1f} ms: {_why_over(f)}"
        )
    if f.broker_missed == len(samples):
        broker = "no broker delivery seen (the line's floor alone)"
    else:
        broker = f"the broker's delivery p99 {f.broker_p99_ms:.1f} ms"
        if f.broker_missed:
            broker += (
                f" ({f.broker_missed} of {len(samples)} stops missed by the probe: their floor "
                "is the line's alone)"
            )
    return Verdict(
        f"{name}: stop p99 <= {GOAL_MS:g} ms beyond the line's and the broker's floor",
        f"{head}; max {f.max_ms:.1f} ms; {broker}; {f.behind} stop(s) behind bytes already on "
        f"the line, {f.queries} of them a poll query; {query_after(samples)} behind a query "
        "written after the broker handed the STOP over (the bridge's part)",
        met,
    )


def query_after(samples: list[Sample]) -> int:
    """How many stops had a poll query the bridge wrote after the broker handed the STOP over
    (after the publish when the probe missed it) go out before them: the bridge's part, as it
    had the stop by then."""
    return sum(
        (s.after if s.broker_s is None else s.after_hand_over).startswith(POLL_QUERY)
        for s in samples
    )


def _broker_cell(f: FloorSplit, n: int) -> str:
    if f.broker_missed == n:
        return "-"
    return f"{f.broker_p99_ms:.1f}" + (f" ({f.broker_missed} missed)" if f.broker_missed else "")


def report_loads(
    result: ItemResult,
    phases: list[PhaseResult],
    missed: int,
    hop: PtyHop,
    probe: DeliveryProbe | None = None,
) -> None:
    table = Table(
        f"{result.title}: R/stop publish -> ';' at a turning Rotor-EZ (4800 baud, "
        f"{MEASURED} taking turns); goal: the bridge's part p99 <= {GOAL_MS:g} ms",
        [
            "load",
            "stops",
            "p50 ms",
            "p99 ms",
            "max ms",
            "broker p99 ms",
            "behind bytes (queries)",
            "bridge's p99 ms",
            "p99 goal",
            "bridge CPU %",
            "load avg",
            "pty hop p99/max ms",
            "stamp late p99/max ms",
        ],
    )
    for p in phases:
        f = floor_split(p.samples)
        met = "met" if f.bridge_p99_ms <= GOAL_MS else "NOT MET"
        t0 = min(s.t for s in p.samples)
        hops = hop.between(t0, max(s.t + s.latency_s for s in p.samples))
        said = "--" if hops is None else f"{hops[0]:.1f} / {hops[1]:.1f}"
        broker = _broker_cell(f, len(p.samples))
        row = [p.name, len(p.samples), f.p50_ms, f.p99_ms, f.max_ms, broker]
        row += [f"{f.behind} ({f.queries})", f.bridge_p99_ms]
        late = sorted(s.stamp_late_s * 1000 for s in p.samples if s.stamp_late_s is not None)
        late_cell = f"{percentile(late, 99):.1f} / {late[-1]:.1f}" if late else "--"
        table.add(*row, met, p.cpu_pct, p.loadavg, said, late_cell)
        result.data[p.name] = {
            "host_pty_hop_ms": None if hops is None else [round(v, 2) for v in hops],
            "latencies_ms": [round(v, 3) for v in _ms(p.samples)],
            "broker_ms": [
                None if s.broker_s is None else round(s.broker_s * 1000, 3) for s in p.samples
            ],
            "wire_ahead_ms": [round(s.wire_ahead_s * 1000, 3) for s in p.samples],
            "wire_ahead_bytes": [_text(s.ahead) for s in p.samples],
            "line_after_publish": [_text(s.after) for s in p.samples],
            "handed_ahead_ms": [round(s.handed_ahead_s * 1000, 3) for s in p.samples],
            "handed_ahead_bytes": [_text(s.handed_ahead) for s in p.samples],
            "line_after_hand_over": [_text(s.after_hand_over) for s in p.samples],
            "floor_by": [s.floor_by for s in p.samples],
            "bridge_part_ms": [round(s.bridge_s * 1000, 3) for s in p.samples],
            "stamp_late_ms": [
                None if s.stamp_late_s is None else round(s.stamp_late_s * 1000, 3)
                for s in p.samples
            ],
            "p99_ms": round(f.p99_ms, 3),
            "broker_p99_ms": None if math.isnan(f.broker_p99_ms) else round(f.broker_p99_ms, 3),
            "broker_missed": f.broker_missed,
            "bridge_part_p99_ms": round(f.bridge_p99_ms, 3),
            "over_goal": f.over,
            "over_goal_by_broker": f.over_broker,
            "over_goal_by_line": f.over_line,
            "behind_bytes": f.behind,
            "behind_query": f.queries,
            "behind_query_written_after": query_after(p.samples),
            "rotors": [s.rid for s in p.samples],
            "bridge_cpu_pct": round(p.cpu_pct, 1),
            "loadavg": round(p.loadavg, 2),
            "applied": p.applied,
            "counts": p.counts,
        }
        if p.name != CONTROL:
            result.verdicts.append(row_verdict(p.name, p.samples))
    for p in phases:
        table.notes.append(f"{p.name}: {p.applied}")
    table.notes.append(
        "p50/p99/max ms: the raw figures, publish -> ';'; broker p99: from the publish to the "
        "broker's delivery of the STOP to a subscriber of this benchmark's, served before the "
        "bridge's connections (the kernel's receive stamp: benchmarks/delivery.py); behind "
        "bytes: the stops whose line was still sending, when the broker handed the STOP over, "
        "bytes the bridge had written before it (at the publish for a stop the probe missed; "
        "queries: all of them a poll query AI1;, 8.3 ms at 4800 baud); bridge's p99: p99 of "
        "each stop's latency less its floor (the stop reaches the line neither before the "
        "broker handed it over nor before the line is free of what the bridge wrote until "
        f"then), judged against {GOAL_MS:g} ms; a query the bridge wrote after the hand-over "
        "is the bridge's part (results.json: line_after_hand_over)"
    )
    if probe is not None:
        missed_by_probe = sum(s.broker_s is None for p in phases for s in p.samples)
        ended = f"; its connection ended: {probe.error}" if probe.error else ""
        table.notes.append(
            f"the broker's delivery: the probe missed {missed_by_probe} stop(s) (their floor "
            f"is the line's alone){ended}; its clock offset moved {probe.offset_moved_s * 1e6:.0f}"
            f" us, read to within {probe.offset_error_s * 1e6:.1f} us"
        )
        result.data["broker_probe"] = {
            "missed": missed_by_probe,
            "error": probe.error,
            "offset_moved_us": round(probe.offset_moved_s * 1e6, 1),
            "offset_error_us": round(probe.offset_error_s * 1e6, 2),
        }
    table.notes.append(
        "the controllers and the stops' publisher ran before everything else (nice -10, as "
        "hardware and the operator's machine would)"
        if result.data.get("controllers_first")
        else "the controllers shared one priority with the bridge and the loads (not root)"
    )
    rt = result.data.get("instrument_rt")
    table.notes.append(
        "stamp late: how long after the line delivered the stop byte the controller stamped "
        "its frame (the instrument's own wait for a core or the interpreter lock, inside every "
        "latency: benchmarks/line.py rule 8); "
        + (
            "the lines' relays, the controllers' emulators and the publisher's network thread "
            "ran in the real-time class (benchmarks/harness.py rule 6; STOP_INSTRUMENT_RT=0: not)"
            if rt
            else "the instrument's threads at their ordinary priority (STOP_INSTRUMENT_RT=0, or "
            "not allowed here)"
        )
    )
    table.notes.append(
        "pty hop: a byte through a pty on this machine, written every 5 ms by a probe of its "
        "own beside the stops (benchmarks/ptyhop.py): the bridge's port is a pty, and what the "
        "host's kernel took to pass its stop on (a real serial adapter has no such hop) is in "
        "the stop's time; a row whose tail is near this hop's waited for the host"
    )
    table.notes.append(
        "p99 is nearest-rank: with 60 stops it is the largest; the load average (1 min, 2 cores) "
        f"is the machine's, shared; {missed} turned rotor(s) reached the far end unstopped "
        "(not counted)"
    )
    result.tables.append(table)
    backlog = next((p for p in phases if p.name == BACKLOG_LOAD), None)
    if backlog is None:
        return
    rounds = backlog.counts["rounds"]
    bt = Table(
        "The backlog's own STOP: targets, then STOP (QoS 1) on one connection, to "
        "rotor b (Rotor-EZ, 1 s brake)",
        [
            "round",
            "targets",
            "stops beside",
            "publish s",
            "read s",
            "STOP to read s",
            "STOP -> ';' ms",
            "starts after",
            "moves after",
        ],
    )
    for i, r in enumerate(rounds, 1):
        bt.add(
            f"{i}, alone" if r["alone"] else i,
            f"{r['targets']:,}",
            r["stops_beside"],
            r["publish_s"],
            r["read_s"],
            r["held_s"],
            "no ';' (b was still)" if r["stop_ms"] is None else r["stop_ms"],
            r["starts_after_stop"],
            r["move_frames_after_stop"],
        )
    bt.notes.append(
        "read s: from the first target until the round's end marker reached its rotor (the main "
        f"connection had read everything); b watched until {TAIL_S:g} s after that; "
        f"mosquitto's 'dropped' notices: {backlog.counts['broker_drop_notices']}"
    )
    bt.notes.append(
        "STOP to read s: how long the targets before the STOP were still arriving after it; a "
        "fault that lets them out after a timeout shows only when this is longer than it: the "
        f"round alone has as many targets as keep this bridge reading about {HOLD_S:g} s after "
        f"its STOP (at least {BACKLOG:,})"
    )
    result.tables.append(bt)
    starts = sum(r["starts_after_stop"] for r in rounds)
    moves = sum(r["move_frames_after_stop"] for r in rounds)
    result.verdicts.append(
        Verdict(
            f"after a STOP that follows {BACKLOG:,} targets (or more) the rotor never starts again",
            f"{starts} start(s), {moves} move frame(s) after the stop frame, "
            f"{len(rounds)} round(s)",
            starts == 0 and moves == 0,
        )
    )


def report_pairs(result: ItemResult, got: dict[str, Any], n: int) -> None:
    title = (
        f"The stop's tail: {n} target+stop pairs per engine on Rotor-EZ ({PAIR_ROTORS} per "
        "engine, the engines' rotors taking turns), R/stop publish -> ';'"
    )
    if "error" in got:
        result.data["pairs"] = got
        target = f"worst stop over {n} pairs no worse than commit {OLD_COMMIT}'s"
        result.verdicts.append(Verdict(target, got["error"], None))
        return
    columns = ["engine", "pairs", "p50 ms", "p99 ms", "worst ms", "behind a query"]
    table = Table(title, [*columns, "worst less the line's wait ms"])
    worst, worst_own = {}, {}
    for engine, ms in got["engines"].items():
        mine = got["own"][engine]
        row = [engine, len(ms), percentile(ms, 50), percentile(ms, 99), max(ms)]
        table.add(*row, got["queries"][engine], max(mine))
        worst[engine], worst_own[engine] = max(ms), max(mine)
    table.notes.append(
        "behind a query: stops whose line was still sending a poll query AI1; the bridge wrote "
        "before the publish (8.3 ms at 4800 baud: a stop right behind a whole one takes 10.4 ms "
        "whatever the engine); the last column takes that wait out, as the loads' rows do"
    )
    result.tables.append(table)
    result.data["pairs"] = {e: [round(v, 3) for v in ms] for e, ms in got["engines"].items()}
    result.data["pairs_less_line"] = {e: [round(v, 3) for v in ms] for e, ms in got["own"].items()}
    old, new = worst[OLD_ENGINE], worst[NEW_ENGINE]
    result.verdicts.append(
        Verdict(
            f"worst stop over {n} pairs no worse than commit {OLD_COMMIT}'s (same run)",
            f"{new:.1f} ms against {old:.1f} ms (less the line's wait: "
            f"{worst_own[NEW_ENGINE]:.1f} against {worst_own[OLD_ENGINE]:.1f})",
            new <= old,
        )
    )


if __name__ == "__main__":  # a load's entry (Loader); the item runs in benchmarks
    if sys.argv[1:2] != ["--load"] or sys.argv[2] not in LOADERS:
        sys.exit("run it as: python -m benchmarks stop_under_load [--quick]")
    LOADERS[sys.argv[2]](json.loads(sys.argv[3]))
