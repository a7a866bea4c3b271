"""Set-up shared by reviews 112 and 152's tests: the bridge (with its stop lane, and the
express or the lock lane) behind an MQTT-aware proxy (tests/support/mqtt_proxy.py) in front of
a real broker, a Rotor-EZ tower answering, and an operator's probe on the broker's own port,
past the proxy.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Generic, TypeVar

from bridge.app import App
from bridge.emulators.pty import EmulatedPort
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

KEEPALIVE_S = 30  # the bridge's default keep-alive: it outlives the faults these tests make
AT_10: Mapping[str, Any] = {"start_az_deg": 10}  # the tower's emulator: at 10 deg, its test speed
TOWER: Mapping[str, Any] = {**AT_10, "speed_deg_s": 2.0}  # at 10 deg, 2 deg/s: 300 is 145 s away
P = TypeVar("P", bound=MqttProxy)


@dataclass
class Behind(Generic[P]):
    proxy: P
    probe: Probe
    rig: Rig
    emu: EmulatedPort[Any]
    app: App
    broker: Mosquitto


@contextlib.contextmanager
def bridge_behind(
    tmp_path: Path,
    make_proxy: Callable[[int], P],
    *,
    express: bool = True,
    keepalive_s: int | None = KEEPALIVE_S,
    emu: Mapping[str, Any] = TOWER,
    ready_s: float | None = None,
    up_s: float = 10,
    lock_lane: bool = False,
    driver: str = "rotorez",
) -> Iterator[Behind[P]]:
    """The bridge behind ``make_proxy(broker's port)``, its tower (a ``driver``, a Rotor-EZ
    unless told, with the emulator's options ``emu``) ready within ``ready_s`` (the rig's own by
    default) and its stop lane up, with the express (``express``) or the lock lane
    (``lock_lane``) too, each within ``up_s``; the main connection's keep-alive ``keepalive_s``
    (None: the setting left out). Closed (probe, proxy, broker) on the way out."""
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = make_proxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            rig.express = express
            if keepalive_s is not None:
                rig.mqtt_extra = {"keepalive_s": keepalive_s}
            tower = rig.add("tower", driver, emu=dict(emu))
            app = rig.start()
            rig.ready("tower", timeout_s=ready_s)
            wait_until(app.lane.connected.is_set, up_s, "the stop lane up")
            if lock_lane:
                wait_until(app.lock_lane.connected.is_set, up_s, "the lock lane up")
            if express:
                wait_until(app.express.up.is_set, up_s, "the stop express up")
            yield Behind(proxy, probe, rig, tower, app, broker)
    finally:
        probe.close()
        proxy.close()
        broker.stop()


def lanes_behind(
    tmp_path: Path,
    make_proxy: Callable[[int], P],
    *,
    keepalive_s: int | None = None,
    emu: Mapping[str, Any] = AT_10,
    lock_lane: bool = True,
) -> contextlib.AbstractContextManager[Behind[P]]:
    """Review 152's ``bridge_behind``: no express (the rig's default), the stop and lock lanes
    up, the bridge's own keep-alive and the emulator's test speed unless told, and the longer
    waits of a loaded machine (ready within slow(30) s, the lanes up within slow(15) s)."""
    return bridge_behind(
        tmp_path,
        make_proxy,
        express=False,
        keepalive_s=keepalive_s,
        emu=emu,
        ready_s=slow(30),
        up_s=slow(15),
        lock_lane=lock_lane,
    )


def said_offline(probe: Probe, mark: int) -> list[str]:
    """The topics on which dashboards were shown the bridge ``offline`` since ``mark``."""
    return [
        m.topic
        for m in probe.messages[mark:]
        if m.topic in ("rotor/availability", "rotor/bridge/state") and m.payload == b"offline"
    ]


def main_up_after_a_doubt(
    probe: Probe, mark: int, app: App, within_s: float, released: threading.Event
) -> bool:
    """Review 152's end: up to ``within_s`` for the bridge to say ``offline`` since ``mark``
    (not an error if it does not), then whether the main connection is up; the backlog held for
    it read after (``released`` set). The test says what it was shown (``said_offline``)."""
    with contextlib.suppress(AssertionError, TimeoutError):
        wait_until(lambda: said_offline(probe, mark), within_s, "the bridge said offline")
    main_up = app.client.connected.is_set()
    released.set()  # the backlog read
    return main_up
