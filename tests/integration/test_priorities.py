"""Which of the bridge's threads a busy machine runs first (bridge/priority.py): the stop's path
(the stop lane's network thread, which takes a STOP off the broker, and the serial-lines thread,
which writes it) keeps the process's priority; the main connection's network thread (a backlog
of targets), the front ends and the threads they start wait for a core behind it. A real
mosquitto, the emulated Rotor-EZ on a pty, a rotctld client on a socket."""

from __future__ import annotations

import os
import socket
import threading

from bridge.priority import BACKGROUND_NICE
from tests.support import free_port, wait_until
from tests.support.rig import Rig
from tests.support.waiting import slow


def nice(thread: threading.Thread) -> int:
    assert thread.native_id is not None
    return os.getpriority(os.PRIO_PROCESS, thread.native_id)


def named(name: str) -> threading.Thread:
    (thread,) = [t for t in threading.enumerate() if t.name == name and t.is_alive()]
    return thread


def test_the_stop_path_runs_before_the_main_connection_and_the_front_ends(rig: Rig) -> None:
    port = free_port()
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0}, rotctld_port=port)
    app = rig.start()
    rig.ready("tower")
    usual = os.getpriority(os.PRIO_PROCESS, os.getpid())
    wait_until(app.lane.connected.is_set, slow(10), "the stop lane connected")
    lane = named(f"paho-mqtt-client-{app.lane.client_id}")
    main = named(f"paho-mqtt-client-{rig.settings.mqtt.effective_client_id()}")
    lines = named("serial-lines")
    listener = named("rotctld-tower")
    with socket.create_connection(("127.0.0.1", port), timeout=slow(10)) as conn:
        conn.sendall(b"p\n")
        assert conn.recv(64)  # the client's thread answered: it runs
        (client,) = [t for t in threading.enumerate() if t.name.startswith("rotctld-tower-")]
        lowered = [main, listener, client]
        wait_until(
            lambda: all(nice(t) >= usual + BACKGROUND_NICE for t in lowered),
            slow(10),
            "the main connection and the rotctld threads lowered",
        )
    assert nice(lane) == usual
    assert nice(lines) == usual
