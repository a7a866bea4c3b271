"""Set-up shared by review 112's tests: the bridge (with its stop lane and express) behind an
MQTT-aware proxy (tests/support/mqtt_proxy.py) in front of a real broker, a Rotor-EZ tower
answering, and an operator's probe on the broker's own port, past the proxy.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Generic, TypeVar

from bridge.app import App
from bridge.emulators.pty import EmulatedPort
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.waiting import wait_until

KEEPALIVE_S = 30  # the bridge's default keep-alive: it outlives the faults these tests make
P = TypeVar("P", bound=MqttProxy)


@dataclass
class Behind(Generic[P]):
    proxy: P
    probe: Probe
    rig: Rig
    emu: EmulatedPort[Any]
    app: App


@contextlib.contextmanager
def bridge_behind(tmp_path: Path, make_proxy: Callable[[int], P]) -> Iterator[Behind[P]]:
    """The bridge behind ``make_proxy(broker's port)``, its tower (a Rotor-EZ at 10, 2 deg/s)
    ready and its stop lane and express up; closed (probe, proxy, broker) on the way out."""
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = make_proxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            rig.express = True
            rig.mqtt_extra = {"keepalive_s": KEEPALIVE_S}
            emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            app = rig.start()
            rig.ready("tower")
            wait_until(app.lane.connected.is_set, 10, "the stop lane up")
            wait_until(app.express.up.is_set, 10, "the stop express up")
            yield Behind(proxy, probe, rig, emu, app)
    finally:
        probe.close()
        proxy.close()
        broker.stop()
