"""Review 127: since "demo: a broker answers when a CONNECT gets a CONNACK" and "give a broker's
CONNACK as long as the bridge does" (cf33222e, 1dc74693), the demo's first look at its MQTT port
waits up to CONNACK_TIMEOUT_S (10 s) for a CONNACK, then 1 s more (LOOK_AGAIN_S), saying nothing.
A user who presses Ctrl-C in that silence (the demo looks hung) is ignored: the signal only
marks the demo's end, so the demo finishes its look, starts a private mosquitto, the emulators
and the bridge, prints its whole banner ("bridged to a private mosquitto ...", the commands to
turn the rotator) and only then stops. Before those commits the look was a TCP connect, and
Ctrl-C took effect at once.

A real demo process; on its port a program that takes connections and never answers (a hung
broker, an SSH tunnel whose far end is gone: the case rule 6 was written for)."""

from __future__ import annotations

import signal
import socket
import threading
from pathlib import Path

from tests.demo_process import DemoProcess
from tests.support.waiting import slow


def test_ctrl_c_while_the_demo_looks_at_a_silent_port_ends_it_without_starting(
    tmp_path: Path,
) -> None:
    looked = threading.Event()
    with socket.create_server(("127.0.0.1", 0)) as silent:
        port = silent.getsockname()[1]
        taken: list[socket.socket] = []

        def take() -> None:
            try:
                conn, _ = silent.accept()  # the demo's CONNECT: read by no one, never answered
            except OSError:
                return
            taken.append(conn)
            looked.set()

        threading.Thread(target=take, daemon=True).start()
        proc = DemoProcess(["--mqtt-port", str(port)], tmp_path / "tmp")
        try:
            assert looked.wait(slow(20)), f"the demo never looked at its port: {proc.output}"
            proc.proc.send_signal(signal.SIGINT)  # the user's Ctrl-C, in the demo's silence
            proc.wait(slow(30))
        finally:
            proc.close()
            for conn in taken:
                conn.close()
    assert "bridged to" not in proc.output, (
        f"after Ctrl-C the demo went on to start and announce itself:\n{proc.output}"
    )
    assert "stopping (SIGINT)" in proc.output or proc.proc.returncode != 0, proc.output
