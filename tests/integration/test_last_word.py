"""The last word on stop and lock across the two MQTT connections (interfaces/mqtt/lastword.py),
with real parts: mosquitto, the bridge (App), an emulated Rotor-EZ on a pty.

A flood that keeps the main connection behind is stood in for by holding its hand-off still
(the main connection reads nothing more) at a chosen message, while the stop lane reads on;
then letting it go. Each ordering below ended wrong before lastword.py: unlocked when the last
word was ON, a stop waiting behind the flood, a target published before a stop carried out
after it, a retained stop stopping the rotor at every reconnect of the lane.
"""

from __future__ import annotations

import json
import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from bridge.app import App
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces.mqtt.heartbeat import Stamp
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until


@contextmanager
def main_held_at(app: App, topic: str, payload: bytes) -> Iterator[threading.Event]:
    """The main connection stops reading at the message ``topic``/``payload`` until the block
    ends (yields the event set once it is held there)."""
    release, held = threading.Event(), threading.Event()
    handle = app.client._handler  # the main connection's hand-off (client.py rule 5)

    def stuck(t: str, p: bytes, retain: bool, operator: str | None, stamp: Stamp | None) -> None:
        if t == topic and p == payload and not held.is_set():
            held.set()
            release.wait(slow(30))
        handle(t, p, retain, operator, stamp)

    app.client._handler = stuck
    try:
        yield held
    finally:
        release.set()


def bearings(emu: object) -> list[bytes]:
    return [f.data for f in emu.frames(*BEARING_OUTCOMES)]  # type: ignore[attr-defined]


def marker_back(rig: Rig, app: App) -> None:
    """Everything published so far has been read by the main connection: a refused target
    sent last comes back as the newest error."""
    t = time.monotonic()
    rig.probe.publish("rotor/target", "sync")
    rig.probe.wait_for("rotor/error", lambda m: b"sync" in m.payload, 10, after=t)
    wait_until(lambda: not app.mqtt._word.holding, 10, "the last marker came back")


def test_lock_off_then_on_behind_a_backlog_ends_locked(rig: Rig) -> None:
    """The lane reads ON before the main connection reads the OFF published before it."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
    app = rig.start()
    rig.ready("tower")
    rig.probe.publish("rotor/lock", "ON")
    rig.probe.wait_value("rotor/lock/state", "ON", 10)
    with main_held_at(app, "rotor/target", b"100") as held:
        rig.probe.publish("rotor/target", "100")  # (refused: locked) the main one stops here
        wait_until(held.is_set, 10, "the main connection is held")
        rig.probe.publish("rotor/lock", "OFF")
        for az in range(120, 420):  # the slider still moving
            rig.probe.publish("rotor/target", str(az % 360), qos=0)
        rig.probe.publish("rotor/lock", "ON")
        wait_until(lambda: app.mqtt._word.holding, 10, "the lane's ON carried out")
    # the marker is back once the main connection has read all of it (the copy of the ON
    # included); its refusals are too many for R/error (rate-limited) to serve as a sync
    wait_until(lambda: not app.mqtt._word.holding, 10, "the main connection caught up")
    assert app.rotators[0].status.locked
    rig.probe.wait_value("rotor/lock/state", "ON", 10)
    app.store.flush()  # (saved on the state file's own thread)
    state = json.loads((rig.tmp / "state.json").read_text())
    assert state["rotators"]["tower"]["locked"] is True, state
    assert bearings(emu) == []  # not one of the slider's targets went out, ever


def test_lock_on_then_off_behind_a_backlog_ends_unlocked_and_the_next_target_is_obeyed(
    rig: Rig,
) -> None:
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
    app = rig.start()
    rig.ready("tower")
    with main_held_at(app, "rotor/target", b"100") as held:
        rig.probe.publish("rotor/target", "100")
        wait_until(held.is_set, 10, "the main connection is held")
        rig.probe.publish("rotor/lock", "ON")
        rig.probe.publish("rotor/lock", "OFF")
        rig.probe.publish("rotor/target", "250")  # published after the OFF: obeyed
        wait_until(lambda: app.rotators[0].status.locked, 10, "the lane's ON carried out")
    emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 250) <= 3, 30)
    rig.probe.wait_value("rotor/lock/state", "OFF", 10)
    assert not app.rotators[0].status.locked
    # 100 went out before the ON (it was published first, and read first); never after it
    sent = bearings(emu)
    assert sent[-1] == b"AP1250\r", sent


def stop_behind_a_held_target(rig: Rig, app: App, emu: object) -> None:
    """The rotor turns to 200; the main connection is held on a target of 300 published next;
    a stop published after that reaches the controller on the lane meanwhile."""
    rig.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving, 10)  # type: ignore[attr-defined]
    with main_held_at(app, "rotor/target", b"300") as held:
        rig.probe.publish("rotor/target", "300")
        wait_until(held.is_set, 10, "the main connection is held on 300")
        stops = len(emu.frames("stop"))  # type: ignore[attr-defined]
        rig.probe.publish("rotor/stop", "")
        emu.wait_until(  # type: ignore[attr-defined]
            lambda d, now: len(d.frames("stop")), lambda n: n > stops, 10
        )


def test_a_target_published_before_a_lane_stop_never_runs_after_it(rig: Rig) -> None:
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
    app = rig.start()
    rig.ready("tower")
    stop_behind_a_held_target(rig, app, emu)
    emu.wait_for(lambda s: not s.is_moving, 10)
    marker_back(rig, app)
    stopped = emu.state().az_deg
    assert not emu.state().is_moving and emu.state().az_deg == stopped
    assert not [d for d in bearings(emu) if b"300" in d]  # never went out
    rig.probe.publish("rotor/target", "250")  # and the next one is obeyed
    emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 250) <= 3, 30)


def tower(rig: Rig, speed_deg_s: float = 20.0) -> tuple[Any, App]:
    """An emulated Rotor-EZ at 10 degrees, bridged, settled, the stop lane up."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": speed_deg_s})
    app = rig.start()
    rig.ready("tower")
    wait_until(app.lane.connected.is_set, 10, "the lane is up")
    return emu, app


def kick_the_lane(app: App) -> None:
    """The stop lane's connection drops (its socket shut under it); paho reconnects it."""
    sock = app.lane._client.socket()
    assert sock is not None
    sock.shutdown(socket.SHUT_RDWR)
    wait_until(lambda: not app.lane.connected.is_set(), 10, "the lane is down")


def test_a_stop_the_lane_missed_does_not_make_the_next_one_wait_behind_the_backlog(
    rig: Rig,
) -> None:
    emu, app = tower(rig)
    kick_the_lane(app)
    rig.probe.publish("rotor/stop", "")  # only the main connection has this one
    wait_until(app.lane.connected.is_set, 15, "the lane is back")
    stop_behind_a_held_target(rig, app, emu)
    marker_back(rig, app)
    assert not [d for d in bearings(emu) if b"300" in d]


def test_a_retained_stop_does_not_stop_the_rotor_again_when_the_lane_reconnects(
    rig: Rig,
) -> None:
    emu, app = tower(rig, speed_deg_s=10.0)
    t = time.monotonic()
    rig.probe.publish("rotor/stop", "STOP", retain=True)  # a dashboard button set to retain
    rig.probe.wait_for("rotor/error", lambda m: b"retained" in m.payload, 10, after=t)
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving, 10)
    stops = len(emu.frames("stop"))
    kick_the_lane(app)
    wait_until(app.lane.connected.is_set, 15, "the lane is back")
    marker_back(rig, app)
    assert emu.state().is_moving  # still on its way
    emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 300) <= 3, 60)
    assert len(emu.frames("stop")) == stops
    rig.probe.publish("rotor/stop", "", retain=True)  # (cleared)
