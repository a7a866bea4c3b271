"""The stop express (interfaces/mqtt/express.py): a STOP's frame reaches the controller while
nothing in the bridge's process can run. Real parts: mosquitto, the bridge (App, in this process),
the express (its own process) and a Rotor-EZ emulator in a process of its own on a pty.

The bridge's interpreter is held the hard way: a call into C through ctypes.PyDLL keeps the
interpreter lock for as long as it blocks, here a read() on a pipe. Every thread of this
process (the stop lane, the main connection, the serial-lines thread, the test's own) stands
still until a watcher process, which publishes the STOP and reads the emulator's frame log,
lets it go: when the stop frame came, or after its deadline without one. The watcher, not
this process, says which.
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from bridge.app import App
from bridge.core.errors import Refused
from bridge.core.model import Source, Target
from bridge.emulators.pty import EmulatedPort
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces.mqtt import lane as lane_module
from bridge.runtime.rotator import Rotator
from tests.faults.conftest import mosquitto_password_file
from tests.integration.test_last_word import bearings, main_held_at, marker_back
from tests.support import free_port
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Line, Rig
from tests.support.waiting import slow, wait_until

# the watcher: drains the frame log until armed, publishes the STOP, then waits for the stop
# frame in the log; writes b"1" (seen) or b"0" (its deadline passed) on the release pipe
WATCHER = r"""
import os, select, subprocess, sys, time
arm, release = int(sys.argv[1]), int(sys.argv[2])
port, topic, deadline_s = sys.argv[3], sys.argv[4], float(sys.argv[5])
while True:
    ready = select.select([arm, 0], [], [])[0]
    if 0 in ready and not os.read(0, 65536):
        sys.exit(1)
    if arm in ready:
        os.read(arm, 1)
        break
subprocess.run(["mosquitto_pub", "-p", port, "-t", topic, "-m", "STOP", "-q", "1"], check=True)
end, log, seen = time.monotonic() + deadline_s, b"", False
while not seen and time.monotonic() < end:
    if select.select([0], [], [], max(0.0, end - time.monotonic()))[0]:
        data = os.read(0, 65536)
        if not data:
            break
        log += data
        seen = b"-> stop" in log
os.write(release, b"1" if seen else b"0")
"""


@pytest.fixture(autouse=True)
def _express_on(monkeypatch: pytest.MonkeyPatch) -> None:
    """The rigs here start the express: it is what they test (the rig's default is off)."""
    monkeypatch.setattr(Rig, "express", True)


def express_ready(app: App, rid: str = "tower") -> None:
    """Subscribed, and holding the rotator's port: from now on it writes a stop."""
    wait_until(app.express.up.is_set, 10, "the express is up")
    wait_until(lambda: rid in app.express.held, 10, "the express holds the port")


def _emulator_process(rig: Rig, rid: str, model: str, options: dict[str, Any]) -> Line:
    """The controller in a process of its own (the rig's run in this one), its frames logged
    on a pipe the watcher reads."""
    link = rig.tmp / f"serial-by-id-{rid}"
    emu = subprocess.Popen(
        [sys.executable, "-m", "bridge.emulators", model, "--link", str(link), "--log-frames"]
        + ["--speed-deg-s", "20", "--brake-delay-s", "0.5", "--start-az-deg", "10"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    rig.scope.callback(emu.wait, 10)
    rig.scope.callback(emu.terminate)
    assert emu.stdout is not None
    emu.stdout.readline()  # the device: the link is there now (emulators/cli.py rule 1)
    line = Line(rid, model, None, link)  # type: ignore[arg-type]  # no emulator object here
    line.relay = emu
    return line


def test_a_stop_frame_reaches_the_controller_while_the_bridge_process_is_held(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    if not Path("/usr/bin/mosquitto_pub").exists():
        pytest.fail("mosquitto_pub (Debian: mosquitto-clients) is needed by this test")
    with Rig(tmp_path, broker, probe, open_line=_emulator_process) as rig:
        rig.add("tower", brake_delay_s=0.5)
        app = rig.start()
        rig.ready("tower")
        express_ready(app)
        emu = rig.lines["tower"].relay
        arm_r, arm_w = os.pipe()
        release_r, release_w = os.pipe()
        watcher = subprocess.Popen(
            [sys.executable, "-c", WATCHER, str(arm_r), str(release_w), str(broker.port)]
            + ["rotor/stop", str(slow(20))],
            stdin=emu.stderr,
            pass_fds=[arm_r, release_w],
        )
        os.close(arm_r)
        os.close(release_w)
        rig.probe.publish("rotor/target", "300")
        rig.probe.wait_value("rotor/state", "moving", 10)
        answer = ctypes.create_string_buffer(1)
        libc = ctypes.PyDLL(None)  # PyDLL: the interpreter lock is kept through the call
        os.write(arm_w, b"1")
        got = libc.read(release_r, answer, 1)  # every thread of this process stands still
        assert watcher.wait(slow(10)) == 0
        assert got == 1 and answer.raw == b"1", "no stop frame while the bridge's process was held"
        os.close(arm_w)
        os.close(release_r)
        rig.probe.wait_value("rotor/state", "idle", 10)
        # the express's word that it wrote: read by the bridge's reader thread once the process
        # runs again, which on a loaded machine may come after the rotor's state
        wait_until(lambda: app.express.wrote, 10, "the express's word that it wrote the stop")
        assert app.express.wrote[0][0] == "tower"


def test_after_an_unplug_and_replug_the_express_writes_on_the_new_port(rig: Rig) -> None:
    """The old port's copy is given back before it is closed, the new one handed over: the
    express writes the stop after the replug on the new port."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    t = time.monotonic()
    emu.unplug()
    rig.probe.wait_value("rotor/availability", "offline", after=t)
    wait_until(lambda: "tower" not in app.express.held, 10, "the old port given back")
    t = time.monotonic()
    emu.replug()
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15, after=t)
    wait_until(lambda: "tower" in app.express.held, 10, "the new port handed over")
    rig.ready("tower", timeout_s=15)
    rig.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving, 10)
    stops = len(emu.frames("stop"))
    rig.probe.publish("rotor/stop", "")
    wait_until(lambda: app.express.wrote, 10, "the express wrote")
    emu.wait_for(lambda s: not s.is_moving, 10)
    rig.probe.wait_value("rotor/state", "idle", 10)
    wait_until(lambda: len(emu.frames("stop")) > stops, 10, "a stop frame")
    # written on the new port: a write on the old one (hung up) fails and is not said
    assert [rid for rid, _t in app.express.wrote] == ["tower"]


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_the_express_logs_in_as_the_bridge_does(tmp_path: Path, protocol: str) -> None:
    """A broker that takes only a user with a password, and an ACL by user: the express gets the
    password from the bridge (never on its command line), connects and writes; under MQTT 3.1.1
    too (the protocol the main connection speaks)."""
    passwd = mosquitto_password_file(tmp_path / "passwd", {"station": "s3cret"})
    (tmp_path / "acl").write_text("user station\ntopic readwrite rotor/#\n")
    conf = (
        f"user root\nallow_anonymous false\npassword_file {passwd}\nacl_file {tmp_path / 'acl'}\n"
    )
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf).start()
    probe = Probe(broker.port, "rotor/#", username="station", password="s3cret")
    try:
        with Rig(tmp_path, broker, probe) as rig:
            rig.mqtt_extra = {"username": "station", "password": "s3cret", "protocol": protocol}
            emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
            app = rig.start()
            rig.ready("tower")
            express_ready(app)
            child = app.express._child
            assert child is not None and "s3cret" not in " ".join(map(str, child.args))
            probe.publish("rotor/target", "200")
            emu.wait_for(lambda s: s.is_moving, 10)
            probe.publish("rotor/stop", "")
            wait_until(lambda: app.express.wrote, 10, "the express wrote")
            emu.wait_for(lambda s: not s.is_moving, 10)
            info = json.loads(probe.wait_for("rotor/bridge/info", lambda m: True, 10).payload)
            assert not [p for p in info["problems"] if "express" in p]
    finally:
        probe.close()
        broker.stop()


@pytest.mark.parametrize("model", ["rotorez", "rotorcard", "gs232b", "easycomm2", "easycomm3"])
def test_two_stop_frames_cost_nothing_on_the_models_the_express_writes_to(
    rig: Rig, model: str
) -> None:
    """ModelSpec.stop_anytime: the express's frame and the session's reach the controller; the
    rotor stops where it was, nothing is reported as an error, no reading is bogus, and the
    next target is carried out."""
    rig.tapped = model in ("rotorez", "rotorcard")  # what the controller sent, for rig.bogus
    emu = rig.add("tower", model, emu={"start_az_deg": 10})
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    t = time.monotonic()
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving, 10)
    rig.probe.publish("rotor/stop", "")
    wait_until(lambda: app.express.wrote, 10, "the express wrote")
    emu.wait_for(lambda s: not s.is_moving, 10)
    rig.probe.wait_value("rotor/state", "idle", 15, after=t)
    rig.probe.publish("rotor/target", "90")
    rig.arrived("tower", 90)
    assert not rig.probe.on("rotor/error"), [m.text for m in rig.probe.on("rotor/error")]
    if model in ("rotorez", "rotorcard"):  # the tap reads this family's replies (tap.py)
        assert not rig.bogus("tower")  # a banner answering the second ';' is no bearing


def test_an_express_that_dies_is_said_started_again_and_writes_again(rig: Rig) -> None:
    """Killed (an out-of-memory killer, a bug): B/bridge/info says so while it is down, a stop
    still stops the rotor (the stop lane in the bridge's process), and it is started again,
    given the port again, and writes the next stop's frame; B/bridge/info then says nothing
    of it."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    child = app.express._child
    assert child is not None
    child.kill()
    info = rig.probe.wait_for("rotor/bridge/info", lambda m: b"stop express ended" in m.payload)
    (said,) = [p for p in json.loads(info.payload)["problems"] if "express" in p]
    assert "stop lane" in said and "started again" in said
    rig.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving, 10)
    rig.probe.publish("rotor/stop", "")
    emu.wait_for(lambda s: not s.is_moving, 10)
    wait_until(lambda: app.express.starts == 2, 10, "started again")
    express_ready(app)
    rig.probe.wait_for(
        "rotor/bridge/info",
        lambda m: not [p for p in json.loads(m.payload)["problems"] if "express" in p],
    )
    app.express.wrote.clear()
    rig.probe.publish("rotor/target", "100")
    emu.wait_for(lambda s: s.is_moving, 10)
    rig.probe.publish("rotor/stop", "")
    wait_until(lambda: app.express.wrote, 10, "the new express wrote the stop")
    emu.wait_for(lambda s: not s.is_moving, 10)


class DeadFlow:
    """A TCP relay to the broker that, once told, swallows the traffic of the connection whose
    CONNECT carried ``marker`` both ways and keeps its sockets open (a firewall or NAT that
    dropped one flow): no end of file, only the keepalive notices."""

    def __init__(self, upstream: int) -> None:
        self.upstream, self.port = upstream, free_port()
        self.dead: set[bytes] = set()
        self.server = socket.create_server(("127.0.0.1", self.port))
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                client, _ = self.server.accept()
            except OSError:
                return
            broker = socket.create_connection(("127.0.0.1", self.upstream))
            first = client.recv(65536)
            broker.sendall(first)
            for a, b in ((client, broker), (broker, client)):
                threading.Thread(target=self._pump, args=(a, b, first), daemon=True).start()

    def close(self) -> None:
        self.server.close()  # (the relayed connections end with the bridge's)

    def _pump(self, a: socket.socket, b: socket.socket, first: bytes) -> None:
        with contextlib.suppress(OSError):
            while data := a.recv(65536):
                if not any(marker in first for marker in self.dead):
                    b.sendall(data)
        for end in (a, b):
            with contextlib.suppress(OSError):
                end.shutdown(socket.SHUT_RDWR)


def test_a_target_held_for_an_express_whose_flow_died_is_dropped_not_sent_late(
    rig: Rig,
) -> None:
    """An attack pass: a firewall dropped the express's flow alone (the main connection and
    the lane lived). A STOP, then a target 0.3 s later: the target waited for the express's
    answer until its keepalive noticed, then went out, 45 s after it was sent. A hold ended by
    the express's loss drops what waited (session/stops.py rule 5), and says so."""
    rig.express = True
    relay = DeadFlow(rig.broker.port)
    rig.scope.callback(relay.close)
    rig.mqtt_extra = {"port": relay.port, "keepalive_s": 5}
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 10.0})
    app = rig.start()
    rig.ready("tower")
    wait_until(app.express.up.is_set, 10, "the express up")
    rig.probe.publish("rotor/target", "100")
    emu.wait_for(lambda s: s.is_moving, 10)
    relay.dead.add(app.express.client_id.encode())
    t = time.monotonic()
    rig.probe.publish("rotor/stop", "STOP")
    emu.wait_for(lambda s: not s.is_moving, 10)
    rig.probe.publish("rotor/target", "200")
    error = rig.probe.wait_for(
        "rotor/error", lambda m: b"stop express lost" in m.payload, timeout_s=60, after=t
    )
    assert json.loads(error.payload)["command"] == "target az 200"
    assert not [f for f in emu.frames() if f.time_s >= t and f.data.startswith(b"AP1")]


def test_the_express_ends_with_the_bridge(rig: Rig) -> None:
    rig.add("tower")
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    child = app.express._child
    assert child is not None
    rig.stop()
    assert child.wait(slow(5)) == 0  # its socket's end of file, not a kill


def test_an_express_killed_while_the_bridge_stops_is_not_said_to_start_again(
    rig: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    """A service manager's SIGKILL to the group (or the out-of-memory killer) ends the express
    while the bridge stops its rotators: the log said "started again in 1 s" of a bridge on its
    way out. Its end is said as one while the bridge stops, and it is not started again."""
    rig.add("tower")
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    child = app.express._child
    assert child is not None
    flush = app.store.flush

    def killed_meanwhile() -> None:  # (a step of the bridge's stop, with the express still up)
        child.kill()
        wait_until(app.express.ended.is_set, 10, "its end seen")
        flush()

    app.store.flush = killed_meanwhile  # type: ignore[method-assign]
    rig.stop()
    said = [r.getMessage() for r in caplog.records if "stop express ended" in r.getMessage()]
    assert said and "as the bridge stops" in said[0], said
    assert not [r for r in caplog.records if "started again" in r.getMessage()], said
    assert app.express.starts == 1


def test_a_broker_that_refuses_the_express_is_said_and_stops_take_the_lane(
    tmp_path: Path,
) -> None:
    """A connection limit: the test's probe, the main connection and the two lanes take all
    there are (the lanes start the moment the main connection is accepted, connection.py
    rule 6; the express is told of it by the bridge's next look, and its process starts
    slower), the express's is turned away. B/bridge/info says so; a stop still stops the
    rotor. (mosquitto 2.0 lets in one connection more than its max_connections. With a
    limit the two lanes race for, the lock lane took the stop lane's place in two runs of
    six on a busy machine: this test is of the express turned away, not of that race.)"""
    conf = "allow_anonymous true\nmax_connections 3\n"
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf).start()
    probe = Probe(broker.port, "rotor/#")
    try:
        with Rig(tmp_path, broker, probe) as rig:
            emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
            app = rig.start()
            rig.ready("tower")
            wait_until(app.lane.connected.is_set, 10, "the lane is up")
            info = probe.wait_for("rotor/bridge/info", lambda m: b"stop express" in m.payload, 20)
            (said,) = [p for p in json.loads(info.payload)["problems"] if "express" in p]
            assert "closed its connection" in said or "refused" in said
            assert not app.express.up.is_set()
            probe.publish("rotor/target", "200")
            emu.wait_for(lambda s: s.is_moving, 10)
            probe.publish("rotor/stop", "")
            emu.wait_for(lambda s: not s.is_moving, 10)
    finally:
        probe.close()
        broker.stop()


def test_a_late_express_frame_does_not_stop_a_move_published_after_the_stop(rig: Rig) -> None:
    """STOP, then a target: the express is descheduled (here: stopped by a signal) between
    reading the STOP and writing its frame, while the bridge carries the STOP out and reads
    the target. The move waits until the express has answered for that STOP (its rule 8),
    so its late frame comes before the move, never after it: the rotor turns to the target."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 30.0})
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    child = app.express._child
    assert child is not None
    os.kill(child.pid, signal.SIGSTOP)
    try:
        rig.probe.publish("rotor/stop", "")
        rig.probe.publish("rotor/target", "60")

        def taken() -> bool:  # the move is out, or waits for the express (its rule 8)
            status = rig.probe.last("rotor/status")
            pending = status is not None and json.loads(status.payload).get("target") == 60
            return emu.state().is_moving or (pending and bool(getattr(app.express, "_holds", {})))

        wait_until(taken, 10, "the target taken by the session")
    finally:
        os.kill(child.pid, signal.SIGCONT)
    rig.arrived("tower", 60)
    assert app.express.wrote and app.express.wrote[-1][0] == "tower"  # its frame did go


def test_a_groups_stop_is_written_by_the_express_for_each_member(rig: Rig) -> None:
    """``G/stop`` (interfaces/mqtt/groups.py) is a stop of each member: the express writes each
    member's frame, as for its own ``R/stop``."""
    upper = rig.add("upper", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
    lower = rig.add("lower", emu={"start_az_deg": 190, "speed_deg_s": 20.0})
    rig.sections = {"groups": [{"id": "stack", "rotators": ["upper", "lower"]}]}
    app = rig.start()
    rig.ready("upper")
    rig.ready("lower")
    express_ready(app, "upper")
    express_ready(app, "lower")
    rig.probe.publish("rotor/stack/target", "120")
    upper.wait_for(lambda s: s.is_moving, 10)
    lower.wait_for(lambda s: s.is_moving, 10)
    rig.probe.publish("rotor/stack/stop", "")
    wait_until(lambda: {rid for rid, _t in app.express.wrote} == {"upper", "lower"}, 10, "both")
    upper.wait_for(lambda s: not s.is_moving, 10)
    lower.wait_for(lambda s: not s.is_moving, 10)


def test_a_client_that_takes_the_expresss_client_id_is_said(rig: Rig) -> None:
    """Another client with the express's client id (a copied configuration on another host):
    the broker hands the session over (mosquitto 2.0 just drops the other connection) and the
    express backs off (connection.py rule 7), and B/bridge/info says so."""
    rig.add("tower")
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    thief = Probe(rig.broker_port, "", client_id=app.express.client_id)
    try:
        mark = app.express.client_id.encode()
        info = rig.probe.wait_for("rotor/bridge/info", lambda m: mark in m.payload, 30)
        (said,) = [p for p in json.loads(info.payload)["problems"] if "client id" in p]
        assert said.startswith("stop express: ") and app.express.client_id in said
    finally:
        thief.close()


def test_a_client_that_takes_the_stop_lanes_client_id_is_said_until_it_is_gone(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An attack pass: another client connecting with the lane's client id kept it down, and
    nothing said so anywhere (no error, B/bridge/info's problems empty): stops quietly lost
    their own connection. A review: once said, it stayed said after the other went."""
    monkeypatch.setattr(lane_module, "STABLE_S", 3.0)  # (STABLE_S: two minutes)
    rig.add("tower")
    app = rig.start()
    rig.ready("tower")
    wait_until(app.lane.connected.is_set, 10, "the lane up")
    thief = Probe(rig.broker_port, "", client_id=app.lane.client_id)
    try:
        mark = app.lane.client_id.encode()
        info = rig.probe.wait_for("rotor/bridge/info", lambda m: mark in m.payload, 30)
        (said,) = [p for p in json.loads(info.payload)["problems"] if "client id" in p]
        assert said.startswith("stop lane: ") and app.lane.client_id in said
    finally:
        thief.close()
    t = time.monotonic()
    rig.probe.wait_for("rotor/bridge/info", lambda m: mark not in m.payload, 120, after=t)


@contextlib.contextmanager
def express_alone(app: App, broker: Mosquitto) -> Iterator[Probe]:
    """The broker restarted, the express back and the bridge's two connections not (their
    back-off made long: they start clean and never get what is published now); an operator's
    client of its own (the rig's probe reconnects) for the test to publish with."""
    app.client._client.reconnect_delay_set(60, 60)
    app.lane._client.reconnect_delay_set(60, 60)
    app.express.up.clear()
    broker.restart()
    wait_until(app.express.up.is_set, 15, "the express is back")
    assert not app.client.connected.is_set() and not app.lane.connected.is_set()
    operator = Probe(broker.port, "")
    try:
        yield operator
    finally:
        operator.close()


def held_for_the_brake_window(rig: Rig, brake: float) -> tuple[App, EmulatedPort[Any], Rotator]:
    """A Rotor-EZ turned to 300 and sent 100 mid-turn: stopped first, 100 is held for the
    brake window of ``brake`` seconds (the bridge's app, the emulator, the rotator)."""
    emu = rig.add(
        "tower",
        emu={"start_az_deg": 10, "speed_deg_s": 20.0, "brake_delay_s": brake},
        brake_delay_s=brake,
    )
    app = rig.start()
    rig.ready("tower", slow(brake + 10))  # (past the start-up brake window)
    express_ready(app)
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 40, slow(15))
    rig.probe.publish("rotor/target", "100")  # a Rotor-EZ is stopped first; 100 waits
    emu.wait_for(lambda s: not s.is_moving, slow(10))
    rotator = app.rotators[0]
    assert rotator.status.target_az_deg == 100.0  # held for the brake window
    return app, emu, rotator


def test_a_stop_only_the_express_heard_drops_the_target_the_bridge_held(
    rig: Rig, broker: Mosquitto
) -> None:
    """express.py rule 11: after a broker restart the express is back before the bridge's two
    connections (their back-off, here made long); a STOP published then, and nothing after
    it, reaches the controller through the express alone. The target the bridge held for the
    Rotor-EZ's brake window went out when the window ended, and the rotor turned (an attack
    pass); now that stop is the bridge's too, and the held target is dropped."""
    brake = 3.0
    app, emu, rotator = held_for_the_brake_window(rig, brake)
    stopped_at = emu.state().az_deg
    stop_t = time.monotonic()
    with express_alone(app, broker) as operator:
        operator.publish("rotor/stop", "STOP")
        wait_until(lambda: app.express.wrote, 10, "the express wrote the stop")
    wait_until(lambda: rotator.status.target_az_deg is None, 10, "the held target dropped")
    time.sleep(brake + 1.0)  # a quiet period past the brake window: nothing may go out
    sent = [f.data for f in emu.frames(*BEARING_OUTCOMES) if f.time_s >= stop_t]
    assert sent == [] and abs(emu.state().az_deg - stopped_at) < 5


def test_a_lock_on_only_the_express_heard_is_set_and_refuses_the_next_target(
    rig: Rig, broker: Mosquitto
) -> None:
    """express.py rule 11: a lock ON published while only the express is back after a broker
    restart (the bridge's connections start clean: no copy of it ever comes to them) stopped
    the rotor but left it unlocked, and the next target from any front end turned it. The lock
    is what a user turns on before climbing the tower: it is set, and the next target refused."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    rotator = app.rotators[0]
    assert not rotator.locked
    with express_alone(app, broker) as operator:
        operator.publish("rotor/lock", "ON")  # not retained
        wait_until(lambda: rotator.locked, 10, "the lock set")
    wait_until(lambda: rotator.status.locked, 10, "the status says locked")
    with pytest.raises(Refused):
        rotator.submit(Target(200.0, source=Source.WEB), "target 200")  # (the console's way)
    time.sleep(1.0)  # what a move would take to show: none
    assert abs(emu.state().az_deg - 10) < 1 and not emu.state().is_moving


def test_a_lock_on_only_the_express_heard_is_set_for_a_rotator_it_writes_no_frame_for(
    rig: Rig, broker: Mosquitto
) -> None:
    """express.py rule 11: the relay read only the locks of the rotators it writes a stop frame
    for; a SPID beside a Rotor-EZ, locked while only the express was back after a broker
    restart, stayed unlocked and took the next target. It is set now, and that target refused."""
    rig.add("tower")
    spid = rig.add("mast", "rot2prog")
    app = rig.start()
    rig.ready("tower")
    rig.ready("mast")
    express_ready(app)
    assert "mast" not in app.express.held  # (no frame of its own: a SPID's stop is no byte)
    mast = next(r for r in app.rotators if r.id == "mast")
    with express_alone(app, broker) as operator:
        operator.publish("rotor/mast/lock", "ON")  # not retained
        wait_until(lambda: mast.locked, 10, "the lock set")
    wait_until(lambda: mast.status.locked, 10, "the status says locked")
    az = spid.state().az_deg
    with pytest.raises(Refused):
        mast.submit(Target(200.0, source=Source.WEB), "target 200")
    time.sleep(1.0)  # what a move would take to show: none
    assert abs(spid.state().az_deg - az) < 1 and not spid.state().is_moving


def test_a_groups_stop_only_the_express_heard_stops_the_members_it_writes_no_frame_for(
    rig: Rig, broker: Mosquitto
) -> None:
    """express.py rule 11, an attack pass: after a broker restart the express was back before
    the bridge's connections, and a group's stop then stopped the Rotor-EZ it writes for while
    the group's SPID turned on to the group's target (no frame of its own, and no copy of that
    stop ever comes to the bridge's connections). It is said, and the SPID stopped too."""
    tower = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 6.0})
    mast = rig.add("mast", "rot2prog", emu={"start_az_deg": 10, "az_speed_deg_s": 6.0})
    rig.sections = {"groups": [{"id": "stack", "rotators": ["tower", "mast"]}]}
    app = rig.start()
    rig.ready("tower")
    rig.ready("mast")
    express_ready(app)
    rig.probe.publish("rotor/stack/target", "300")
    tower.wait_for(lambda s: s.is_moving, slow(10))
    mast.wait_for(lambda s: s.is_moving, slow(10))
    rotator = next(r for r in app.rotators if r.id == "mast")
    with express_alone(app, broker) as operator:
        operator.publish("rotor/stack/stop", "STOP")
        mast.wait_for(lambda s: not s.is_moving, slow(10))
        tower.wait_for(lambda s: not s.is_moving, slow(10))
        wait_until(lambda: rotator.status.target_az_deg is None, 10, "the SPID's target gone")
        az = mast.state().az_deg
        time.sleep(1.0)  # what a move would take to show: none
        assert abs(mast.state().az_deg - az) < 1 and not mast.state().is_moving


def test_a_target_after_a_stop_just_after_a_broker_restart_is_not_dropped_by_the_express(
    rig: Rig, broker: Mosquitto
) -> None:
    """express.py rule 11: a second after the bridge's connections came back from a broker
    restart, a STOP read by them both and by the express was also taken as one only the
    express could have heard (the margin), and its late second stop dropped the target sent
    after the STOP, unsaid (an attack pass). A connection that read that rotator's halt and
    has had its topics since stands for the express's: no second stop. The express is held
    by a signal so that it reads the STOP after the bridge took the target (a busy host)."""
    rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 30.0})
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    app.express.up.clear()
    broker.restart()
    wait_until(app.express.up.is_set, 15, "the express is back")
    wait_until(lambda: app.client.heard_since(time.monotonic()), 15, "the main connection is back")
    wait_until(lambda: app.lane.heard_since(time.monotonic()), 15, "the stop lane is back")
    express_ready(app)
    child = app.express._child
    assert child is not None
    operator = Probe(broker.port, "")
    os.kill(child.pid, signal.SIGSTOP)
    try:
        operator.publish("rotor/stop", "STOP")
        operator.publish("rotor/target", "200")
        rotator = app.rotators[0]
        wait_until(lambda: rotator.status.target_az_deg == 200.0, 10, "the target taken")
    finally:
        os.kill(child.pid, signal.SIGCONT)
        operator.close()
    wait_until(lambda: app.express.wrote, 10, "the express wrote its stop")
    rig.arrived("tower", 200)


def test_a_stop_the_express_read_late_after_a_broker_restart_still_drops_the_held_target(
    rig: Rig, broker: Mosquitto
) -> None:
    """express.py rule 11, against a clock (docs/architecture.md rule 15): a STOP published
    after a broker restart while only the express was back reaches the controller through the
    express alone; the bridge's connections, subscribed just after it, never get a copy. The
    bridge judged whether they could have had it by the time the express read it, less a
    second: an express held up longer than that (a busy host, here a signal) read it after the
    connections' SUBACK plus the second, the stop was taken for theirs, and the target the
    bridge held for the Rotor-EZ's brake window went out when the window ended: the rotor
    turned after the STOP."""
    brake = 30.0  # longer than the restart and the reconnects below: the target still waits
    app, emu, rotator = held_for_the_brake_window(rig, brake)
    stop_t = time.monotonic()
    app.client._client.reconnect_delay_set(8, 8)  # the bridge's two back after the express
    app.lane._client.reconnect_delay_set(8, 8)
    app.express.up.clear()
    broker.restart()
    wait_until(app.express.up.is_set, 15, "the express is back")
    express_ready(app)
    assert not app.client.connected.is_set() and not app.lane.connected.is_set()
    child = app.express._child
    assert child is not None
    operator = Probe(broker.port, "")
    os.kill(child.pid, signal.SIGSTOP)  # it will read the STOP late
    try:
        operator.publish("rotor/stop", "STOP")  # (the broker has it for the express alone)
        wait_until(lambda: app.client.heard_since(time.monotonic() - 1.5), 30, "main back")
        wait_until(lambda: app.lane.heard_since(time.monotonic() - 1.5), 30, "the lane back")
    finally:
        os.kill(child.pid, signal.SIGCONT)
        operator.close()
    wait_until(lambda: app.express.wrote, 10, "the express wrote the stop")
    wait_until(
        lambda: rotator.status.target_az_deg is None or emu.state().is_moving,
        slow(brake + 15),
        "the held target dropped (or sent)",
    )
    sent = [f.data for f in emu.frames(*BEARING_OUTCOMES) if f.time_s >= stop_t]
    assert sent == [] and not emu.state().is_moving
    assert rotator.status.target_az_deg is None


def test_a_stop_naming_an_operator_of_64_kib_leaves_the_next_target_free_to_go(rig: Rig) -> None:
    """An attack pass (its rule 11): a STOP whose MQTT 5 user property ``operator`` held 21,845
    non-ASCII characters (65,535 bytes, the most an MQTT string holds), from anyone who may
    send a stop, was said back by the express in a word of 131 KB; the bridge read it cut at
    64 KiB, its reader died on the JSON, and every target after a stop waited for an answer
    that never came: the rotor stopped, and never turned again. The operator is no name, so
    the word names none, and the next target turns the rotor."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    sender = paho.Client(CallbackAPIVersion.VERSION2, client_id="long-name", protocol=paho.MQTTv5)
    sender.connect("127.0.0.1", rig.broker.port)
    sender.loop_start()
    try:
        rig.probe.publish("rotor/target", "200")
        emu.wait_for(lambda s: s.is_moving, 10)
        props = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
        props.UserProperty = [("operator", "\ufb00" * 21_845)]
        sender.publish("rotor/stop", "STOP", qos=1, properties=props).wait_for_publish(5)
        emu.wait_for(lambda s: not s.is_moving, 10)
        rig.probe.publish("rotor/target", "100")
        rig.arrived("tower", 100)
        assert app.express.runner.is_alive()  # (its reader: the words of the next stops)
    finally:
        sender.loop_stop()
        sender.disconnect()


def test_a_target_published_before_a_stop_stays_held_when_the_express_dies_meanwhile(
    rig: Rig,
) -> None:
    """express.py rule 8, lastword.py rules 2 and 5: the express's end ends its own hold,
    never the last word's. The main connection is behind (held on a target of 300 published
    just before a STOP the lane carried out, the express's hold on it waiting for an express
    that reads nothing); the express is killed and started again meanwhile; then the main
    connection reads the 300 and is held again before its copy of the STOP: the 300, read
    while the last word's hold lasts, is refused as older (lastword.py rule 2), never sent
    after the STOP."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
    app = rig.start()
    rig.ready("tower")
    express_ready(app)
    wait_until(app.lane.connected.is_set, 10, "the lane is up")
    session = app._by_id["tower"]._worker.session  # (read only: what waits in it)
    rig.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving, 10)
    t = time.monotonic()
    with main_held_at(app, "rotor/stop", b"STOP") as copy_held:
        with main_held_at(app, "rotor/target", b"300") as held:
            rig.probe.publish("rotor/target", "300")
            wait_until(held.is_set, 10, "the main connection is held on 300")
            child = app.express._child
            assert child is not None
            os.kill(child.pid, signal.SIGSTOP)  # (it reads nothing: its hold waits)
            rig.probe.publish("rotor/stop", "STOP")
            emu.wait_for(lambda s: not s.is_moving, 10)  # (the lane's stop)
            wait_until(lambda: "tower" in app.express._holds, 10, "the express's hold waits")
            child.kill()  # its end ends its own hold
            wait_until(lambda: app.express.starts == 2, 15, "started again")
            express_ready(app)
        wait_until(copy_held.is_set, 10, "the main connection read 300, held on the STOP")
        err = rig.probe.wait_for("rotor/error", lambda m: b"300" in m.payload, 10, after=t)
        assert b"that the stop connection carried out first" in err.payload
        assert session.targets.pending is None  # (refused: nothing of it waits to go out)
        assert not [d for d in bearings(emu) if b"300" in d]
    marker_back(rig, app)
    assert not [d for d in bearings(emu) if b"300" in d]  # never went out
    rig.probe.publish("rotor/target", "250")  # and the next one is obeyed
    emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 250) <= 3, 30)
