"""A station's mosquitto bridged to another broker, the one a remote operator reaches (docs/
remote.md, "Through a broker bridge"): mosquitto's bridge on MQTT 5 carries the remote's
commands with their send time, expiry and operator to the station, the station's retained
state out to the operator, and a retained command published on the far broker still moves
nothing.

Real parts: two mosquitto (the station's with a ``connection`` to the far one), the bridge on
an emulated Rotor-EZ behind the station's broker, ``rotor-bridge remote`` on the far one with
Hamlib's ``rotctl -m 2`` as its client.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.remote.run import Remote
from bridge.remote.settings import RemoteSettings
from tests.support import Probe, retained_snapshot, wait_until
from tests.support.hamlib import run_rotctl
from tests.support.mosquitto import Mosquitto, free_port
from tests.support.rig import Rig

pytestmark = pytest.mark.hamlib


@pytest.fixture
def far(tmp_path: Path) -> Iterator[Mosquitto]:
    m = Mosquitto(tmp_path / "far").start()
    yield m
    m.stop()


@pytest.fixture
def station(tmp_path: Path, far: Mosquitto) -> Iterator[Rig]:
    bridge_conf = (
        "allow_anonymous true\n"
        "connection far\n"
        f"address 127.0.0.1:{far.port}\n"
        "bridge_protocol_version mqttv50\n"
        "topic rotor/# both 0\n"
        "restart_timeout 1\n"
    )
    broker = Mosquitto(tmp_path / "station", extra_conf=bridge_conf).start()
    probe = Probe(broker.port)
    try:
        with Rig(tmp_path, broker, probe) as rig:
            rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0, "speed_deg_s": 20})
            rig.start()
            rig.ready("tower")
            # the station's state has crossed the bridge: the far broker holds it
            wait_until(
                lambda: (
                    retained_snapshot(far.port, "rotor/bridge/state").get("rotor/bridge/state")
                    == b"online"
                ),
                20,
                "the station online on the far broker",
            )
            yield rig
    finally:
        probe.close()
        broker.stop()


def rotctl(path: str, port: int, *commands: str) -> str:
    done = run_rotctl(path, 2, port, *commands)
    assert done.returncode == 0, f"rotctl failed: {done.stdout!r} {done.stderr!r}"
    return done.stdout


def test_the_remote_on_the_far_broker_turns_and_stops_the_station_rotator(
    station: Rig, far: Mosquitto, rotctl_path: str
) -> None:
    port = free_port()
    remote = Remote(
        RemoteSettings(
            operator="DL1ABC",
            mqtt={"host": "127.0.0.1", "port": far.port, "base_topic": "rotor"},
            endpoints=[{"rotator": "tower", "rotctld_port": port}],
        )
    )
    remote.start()
    try:
        rotctl(rotctl_path, port, "P", "300", "0")
        station.emus["tower"].wait_for(lambda s: s.is_moving, 20)
        rotctl(rotctl_path, port, "S")
        emu = station.emus["tower"].wait_for(lambda s: not s.is_moving, 20)
        assert 10 < emu.az_deg < 290  # stopped on its way, by the stop that crossed the bridge
        # the operator's name came along with the command (MQTT 5 user property)
        status = json.loads(station.retained()["rotor/status"])
        assert status["last_operator"] == "DL1ABC"
        # and the station's bearing came back to the remote
        wait_until(
            lambda: remote.rotators[0].status.bearing_deg == station.status("tower").bearing_deg,
            20,
            "the remote sees the station's bearing",
        )
    finally:
        remote.stop()


def test_a_retained_target_on_the_far_broker_moves_nothing(station: Rig, far: Mosquitto) -> None:
    far_probe = Probe(far.port)
    try:
        t = time.monotonic()
        far_probe.publish("rotor/target", "200", retain=True)
        # the station hears it with its retain flag (the bridge forwards it as published) and
        # refuses it: said on the error topic, which crosses back to the far broker
        msg = far_probe.wait_for("rotor/error", lambda m: b"retain" in m.payload, 20, after=t)
        assert b"200" in msg.payload or b"target" in msg.payload
        assert not station.emus["tower"].state().is_moving
        assert station.status("tower").state == "idle"
    finally:
        far_probe.publish("rotor/target", "", retain=True)  # the retained command deleted
        far_probe.close()
