"""The README's demo path: `rotor-bridge demo` with no broker running brings up its own, and a
target published on rotor/target turns the emulated Rotor-EZ."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from bridge.mosquitto import free_port
from tests.support import Probe, retained_snapshot, wait_until


def test_demo_without_a_broker_turns_the_rotor_on_a_published_target(tmp_path: Path) -> None:
    port = free_port()
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROTOR_BRIDGE_")}
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "bridge",
            "demo",
            "--mqtt-port",
            str(port),
            "--speed-deg-s",
            "60",
            "--duration-s",
            "60",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        env=env,
    )
    try:
        wait_until(lambda: _connectable(port), 20, "the demo's broker")
        probe = Probe(port, "rotor/#")
        probe.wait_value("rotor/availability", "online", timeout_s=20)
        probe.wait_value("rotor/state", "idle", timeout_s=20)
        snap = retained_snapshot(port, "rotor/#")
        for topic in (
            "rotor/bearing",
            "rotor/state",
            "rotor/status",
            "rotor/version",
            "rotor/availability",
        ):
            assert topic in snap, topic
        probe.publish("rotor/target", "120")
        probe.wait_for("rotor/state", lambda m: m.text == "moving")
        probe.wait_for("rotor/bearing", lambda m: abs(float(m.text) - 120) <= 3, timeout_s=20)
        msg = probe.wait_for(
            "rotor/status",
            lambda m: (
                json.loads(m.payload)["state"] == "idle"
                and json.loads(m.payload)["last_command_source"] == "mqtt"
            ),
            timeout_s=20,
        )
        assert abs(json.loads(msg.payload)["bearing"] - 120) <= 3
        probe.close()
    finally:
        proc.terminate()
        out, _ = proc.communicate(timeout=15)
    assert proc.returncode == 0, out.decode()
    assert b"private mosquitto" in out


def _connectable(port: int) -> bool:
    from bridge.mosquitto import answers

    return answers("127.0.0.1", port)
