"""``rotor-bridge remote`` with real parts: a mosquitto, the bridge on an emulated Rotor-EZ, the
remote in this process on a free port, and Hamlib's ``rotctl -m 2`` as its client (the judge).
"""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge.app import App
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.remote.run import Remote, StartError
from bridge.remote.settings import RemoteSettings
from tests.support import Probe, wait_until
from tests.support.hamlib import run_rotctl
from tests.support.mosquitto import Mosquitto, free_port
from tests.support.remote import Heartbeat, ask, remote_published
from tests.support.rig import Rig
from tests.support.waiting import slow

pytestmark = pytest.mark.hamlib

OPERATOR = "DL1ABC"


class Probe5:
    """An MQTT 5 subscriber to the command topics: sees the properties a command carries."""

    def __init__(self, port: int, topics: str) -> None:
        self.seen: list[tuple[str, bytes, Any]] = []
        self._lock = threading.Lock()
        self._subscribed = threading.Event()
        c = paho.Client(CallbackAPIVersion.VERSION2, client_id="probe5", protocol=paho.MQTTv5)
        c.on_connect = lambda cl, ud, fl, rc, pr: cl.subscribe(topics)
        c.on_subscribe = lambda *a: self._subscribed.set()
        c.on_message = self._on_message
        c.connect("127.0.0.1", port)
        c.loop_start()
        self.client = c
        assert self._subscribed.wait(slow(10)), "probe5 subscribed"

    def _on_message(self, client: Any, userdata: Any, msg: paho.MQTTMessage) -> None:
        with self._lock:
            self.seen.append((msg.topic, bytes(msg.payload), msg.properties))

    def on(self, topic: str) -> list[tuple[str, bytes, Any]]:
        with self._lock:
            return [m for m in self.seen if m[0] == topic]

    def close(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


def settings(broker: Mosquitto, port: int, **extra: Any) -> RemoteSettings:
    return RemoteSettings(
        operator=OPERATOR,
        mqtt={"host": "127.0.0.1", "port": broker.port, "base_topic": "rotor"},
        endpoints=[{"rotator": "tower", "rotctld_port": port}],
        **extra,
    )


@pytest.fixture
def remote(station: Rig) -> Iterator[tuple[Remote, int, list[str]]]:
    port = free_port()
    r = Remote(settings(station.broker, port))  # type: ignore[arg-type]
    lines = r.start()
    yield r, port, lines
    r.stop()


def rotctl(path: str, port: int, *commands: str) -> str:
    done = run_rotctl(path, 2, port, *commands)
    assert done.returncode == 0, f"rotctl failed: {done.stdout!r} {done.stderr!r}"
    return done.stdout


def test_rotctl_turns_the_station_rotator_and_reads_it_back(
    station: Rig, remote: tuple[Remote, int, list[str]], rotctl_path: str
) -> None:
    r, port, lines = remote
    assert lines == [
        f"{OPERATOR} -> 127.0.0.1: tower (rotorez, 0..360) on rotctld 127.0.0.1:{port}"
    ]
    probe5 = Probe5(station.broker.port, "rotor/target")
    try:
        rotctl(rotctl_path, port, "P", "120", "0")
        station.arrived("tower", 120)
        wait_until(lambda: station.status("tower").state == "idle", 10, "the bridge idle")
        wait_until(lambda: probe5.on("rotor/target"), 5, "the command seen on the broker")
        (_, payload, props) = probe5.on("rotor/target")[0]
        assert payload == b'{"azimuth":120.0}'
        assert 0 < props.MessageExpiryInterval <= 5
        assert ("operator", OPERATOR) in props.UserProperty
        wait_until(lambda: r.rotators[0].status.bearing_deg == station.status("tower").bearing_deg)
        az, el = rotctl(rotctl_path, port, "p").split()
        assert abs(float(az) - 120) <= 3.5 and float(el) == 0
    finally:
        probe5.close()


def test_broker_away_refuses_at_once_and_nothing_moves_when_it_is_back(
    station: Rig, remote: tuple[Remote, int, list[str]]
) -> None:
    r, port, _ = remote
    emu = station.emus["tower"]
    link = r.link
    assert link is not None
    moves = len(emu.frames(*BEARING_OUTCOMES))
    # a command the broker never acknowledges (frozen, then gone): paho would send it again on
    # the next connection (interfaces/mqtt/remote.py rule 3); the client is told it did not go (rule
    # 7)
    station.broker.pause()
    assert ask(port, b"P 250 0\n") == b"RPRT -6\n"  # no PUBACK: refused, the link reset
    station.broker.kill()
    wait_until(lambda: not link.up, 30, "the remote sees the broker gone")
    assert ask(port, b"P 200 0\n") == b"RPRT -6\n"  # refused, not queued for the broker
    assert ask(port, b"S\n") == b"RPRT -6\n"  # a stop is not delivered yet: kept (rule 6)
    assert ask(port, b"p\n") == b"RPRT -6\n"  # no stale number
    log_from = station.broker.log.stat().st_size
    station.broker.restart()
    wait_until(lambda: link.up, 30, "the remote back on the broker")
    station.ready("tower", 30)
    wait_until(lambda: r.rotators[0].current, 10, "the station's bridge heard again")
    # a marker behind anything the remote might have resent, on its one ordered connection:
    # the kept stop went first, and again once the station's bridge was heard (rule 6), and
    # nothing of the moves
    assert ask(port, b"S\n") == b"RPRT 0\n"
    wait_until(lambda: len(remote_published(station.broker, log_from)) >= 3, 10, "the marker stop")
    assert remote_published(station.broker, log_from) == [b"stop", b"stop", b"stop"]
    assert len(emu.frames(*BEARING_OUTCOMES)) == moves


def test_a_reading_is_an_error_once_the_station_is_gone(
    station: Rig, remote: tuple[Remote, int, list[str]]
) -> None:
    r, port, _ = remote
    assert ask(port, b"p\n").count(b"\n") == 2
    station.stop()  # the bridge says offline on its way out
    wait_until(lambda: ask(port, b"p\n") == b"RPRT -5\n", 10, "p refused without the bridge")


def test_a_rotator_the_station_does_not_have_is_a_start_error(station: Rig) -> None:
    s = settings(station.broker, free_port(), info_wait_s=1.0)  # type: ignore[arg-type]
    s.mqtt.base_topic = "elsewhere"
    with pytest.raises(StartError, match=r"elsewhere/tower/info within 1 s.*base_topic"):
        Remote(s).start()


def test_the_command_line_prints_the_endpoints_and_stops_on_sigterm(
    station: Rig, tmp_path: Path
) -> None:
    port = free_port()
    conf = tmp_path / "remote.toml"
    conf.write_text(
        f'operator = "{OPERATOR}"\n[mqtt]\nport = {station.broker.port}\n'
        f"[[endpoints]]\nrotctld_port = {port}\n"
    )
    argv = [sys.executable, "-m", "bridge", "remote", "-c", str(conf)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert (
            line
            == f"{OPERATOR} -> 127.0.0.1: tower (rotorez, 0..360) on rotctld 127.0.0.1:{port}\n"
        )
        assert ask(port, b"p\n").count(b"\n") == 2
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(slow(10)) == 0
        assert proc.stderr is not None and proc.stderr.read().rstrip().endswith(": stopped")
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_a_configuration_error_names_the_key(tmp_path: Path) -> None:
    conf = tmp_path / "remote.toml"
    conf.write_text(
        'operator = "DL1ABC"\n[mqtt]\nprotocol = "3.1.1"\n[[endpoints]]\nrotctld_prot = 4533\n'
    )
    argv = [sys.executable, "-m", "bridge", "remote", "-c", str(conf)]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=slow(30), check=False)
    assert done.returncode == 2
    assert "endpoints[0].rotctld_prot: unknown key: did you mean rotctld_port?" in done.stderr
    assert '\n  mqtt.protocol: must be "5" here' in done.stderr  # its field, said beside the other
    conf.write_text(
        'operator = "DL1ABC"\n[mqtt]\nprotocol = "3.1.1"\n[[endpoints]]\nrotctld_port = 4533\n'
    )
    done = subprocess.run(argv, capture_output=True, text=True, timeout=slow(30), check=False)
    assert done.returncode == 2
    assert done.stderr.splitlines()[1:] == [
        '  mqtt.protocol: must be "5" here: the remote\'s commands carry a message expiry'
    ]


def iso(t_unix: float) -> str:
    return datetime.fromtimestamp(t_unix, UTC).isoformat(timespec="milliseconds")


@pytest.fixture
def heartbeat(probe: Probe) -> Iterator[Heartbeat]:
    """A stand-in station's heartbeat (a live bridge's: remote/rotator.py rule 1)."""
    with Heartbeat(probe) as beating:
        yield beating


def test_a_moving_status_older_than_the_limit_reads_as_an_error(
    broker: Mosquitto, probe: Probe, heartbeat: Heartbeat
) -> None:
    """A stand-in station (its retained topics, no bridge): a still rotor's status counts however
    old it is (the station publishes on change), a moving one's only while it is fresh on the
    remote's own clock: one the broker replays on subscribing is of unknown age, one that came
    as published counts for moving_max_age_s whatever the station's clock says."""
    info = (
        '{"name":"tower","model":"rotorez","model_name":"Rotor-EZ","has_elevation":false,'
        '"can_report_position":true,"can_track":false,"azimuth_range":[0,360],'
        '"elevation_range":null,"keep_out":[],"park":null,"options":[]}'
    )
    probe.publish("rotor/info", info, retain=True)
    probe.publish("rotor/bridge/state", "online", retain=True)
    probe.publish("rotor/availability", "online", retain=True)

    def status(state: str, age_s: float) -> bytes:
        return (
            f'{{"bearing":42.0,"target":null,"parked":false,"state":"{state}",'
            f'"moving":{"true" if state == "moving" else "false"},"connected":true,'
            '"available":true,"locked":false,"version":"1.4S","options":{},"last_error":null,'
            f'"last_command_source":null,"estimated":false,"time":"{iso(time.time() - age_s)}"}}'
        ).encode()

    probe.publish("rotor/status", status("moving", 0), retain=True)  # replayed to the remote
    port = free_port()
    # the age a moving status counts for: the test must ask within it once the status came
    # (it was 1 s: on a busy machine the test's thread and the remote's rotctld answered
    # later than that, and the fresh status read as gone quiet), so as long as it needs
    max_age_s = slow(2)
    r = Remote(settings(broker, port, moving_max_age_s=max_age_s))  # type: ignore[arg-type]
    r.start()
    try:
        wait_until(lambda: r.view.get("rotor/status") is not None, 5, "the replayed status")
        assert ask(port, b"p\n") == b"RPRT -5\n"
        for state, age_s in [("idle", 3600), ("moving", 3600)]:  # a station clock an hour slow
            payload = status(state, age_s)
            probe.publish("rotor/status", payload, retain=True)
            wait_until(
                lambda p=payload: r.view.get("rotor/status") == p, 5, "the status at the remote"
            )
            assert ask(port, b"p\n") == b"42.00\n0.00\n", (state, age_s)
        # nothing more from the station: moving_max_age_s passing is what is tested
        wait_until(lambda: ask(port, b"p\n") == b"RPRT -5\n", 10, "the move gone quiet")
    finally:
        r.stop()


def test_a_forged_info_id_or_name_puts_no_line_of_its_own_in_the_start_lines(
    broker: Mosquitto, probe: Probe, heartbeat: Heartbeat
) -> None:
    """readings.py rule 2, an attack pass on a stand-in station: anyone who may publish the
    station's R/info gave it an id holding a line break and a terminal's escape sequence, and
    the remote printed a forged line of its own on the operator's terminal, the terminal
    turned red. Such an id or name reads as unknown: the model stands for it."""
    forged = "tower\\nDL1ABC -> forged\\u001b[31m"
    info = f'{{"id":"{forged}","name":"{forged}","model":"rotorez","azimuth_range":[0,360]}}'
    for topic, payload in (
        ("rotor/info", info),
        ("rotor/bridge/state", "online"),
        ("rotor/availability", "online"),
    ):
        probe.publish(topic, payload, retain=True)
    port = free_port()
    one = RemoteSettings(
        operator=OPERATOR,
        mqtt={"host": "127.0.0.1", "port": broker.port, "base_topic": "rotor"},
        endpoints=[{"rotctld_port": port}],
    )
    r = Remote(one)
    try:
        lines = r.start()
    finally:
        r.stop()
    assert lines == [
        f"{OPERATOR} -> 127.0.0.1: rotorez (rotorez, 0..360) on rotctld 127.0.0.1:{port}"
    ]


def test_what_the_broker_held_before_a_drop_is_not_read_after_it(
    broker: Mosquitto, probe: Probe, heartbeat: Heartbeat
) -> None:
    """remote/run.py rule 4, on a stand-in station (its retained topics, no bridge): the broker
    comes back without them (no persistence, nobody publishes them again), and the remote must
    not take the station for online on what it read before the drop."""
    for topic, payload in (
        ("rotor/info", '{"name":"tower","model":"rotorez","azimuth_range":[0,360]}'),
        ("rotor/bridge/state", "online"),
        ("rotor/availability", "online"),
        ("rotor/status", '{"bearing":42.0,"state":"idle","connected":true,"available":true}'),
    ):
        probe.publish(topic, payload, retain=True)
    port = free_port()
    r = Remote(settings(broker, port))  # type: ignore[arg-type]
    r.start()
    try:
        link = r.link
        assert link is not None
        wait_until(lambda: ask(port, b"p\n") == b"42.00\n0.00\n", 5, "the station's bearing")
        broker.kill()
        wait_until(lambda: not link.up, 30, "the remote sees the broker gone")
        broker.restart()
        wait_until(lambda: link.up, 30, "the remote back on the broker")
        assert ask(port, b"p\n") == b"RPRT -5\n"  # connected, but no word from the station
    finally:
        r.stop()


def test_another_operators_lease_is_refused_at_once_and_the_stations_refusals_are_logged(
    station: Rig, remote: tuple[Remote, int, list[str]], caplog: pytest.LogCaptureFixture
) -> None:
    """remote/rotator.py rule 6 and run.py rule 7: what the station would refuse in silence
    (its R/error), the client hears at once or the operator reads in the remote's log."""
    r, port, _ = remote
    emu = station.emus["tower"]
    moves = len(emu.frames(*BEARING_OUTCOMES))
    other = paho.Client(CallbackAPIVersion.VERSION2, client_id="g4xyz", protocol=paho.MQTTv5)
    other.connect("127.0.0.1", station.broker.port)
    other.loop_start()
    try:
        other.publish("rotor/control/claim", '{"operator": "G4XYZ", "minutes": 5}', qos=1)
        wait_until(lambda: b"G4XYZ" in (r.view.get("rotor/control") or b""), 10, "the lease")
        assert ask(port, b"P 100 0\n") == b"RPRT -9\n"  # rejected, as the station's rotctld
        assert ask(port, b"S\n") == b"RPRT 0\n"  # a stop from anyone
        other.publish("rotor/control/release", '{"operator": "G4XYZ"}', qos=1)
        wait_until(lambda: b'"holder":null' in (r.view.get("rotor/control") or b""), 10, "free")
        other.publish("rotor/lock", "ON", qos=1)
        wait_until(lambda: r.view.get("rotor/lock/state") == b"ON", 10, "the station locked")
        assert ask(port, b"P 100 0\n") == b"RPRT -9\n"  # refused at once, as for the lease
        other.publish("rotor/lock", "OFF", qos=1)
        wait_until(lambda: r.view.get("rotor/lock/state") == b"OFF", 10, "unlocked")
        other.publish("rotor/control/claim", '{"operator": "G4XYZ", "minutes": 5}', qos=1)
        other.publish("rotor/control/release", '{"operator": "G4XYZ"}', qos=1)
        other.publish("rotor/lock", "ON", qos=1)  # the station judges again: R/error, logged
        other.publish("rotor/target", "100", qos=1)
        wait_until(lambda: "the station says: rotator is locked" in caplog.text, 10, "logged")
        # an attack pass: the station's refusal quotes the sender's key, and the remote's
        # log took its line break: a line of the remote's own, forged by anyone on the broker
        other.publish("rotor/control/claim", '{"minutes": 5, "\\nFAKE: forged": 1}', qos=1)
        wait_until(lambda: "\\nFAKE: forged" in caplog.text, 10, "the refusal, escaped")
        assert not any("\nFAKE" in r.getMessage() for r in caplog.records)
    finally:
        other.loop_stop()
        other.disconnect()
    assert len(emu.frames(*BEARING_OUTCOMES)) == moves


def test_a_dead_station_a_restored_broker_still_calls_online_is_no_reading_and_no_move(
    broker: Mosquitto, probe: Probe
) -> None:
    """A broker restored from its file holds what the station's bridge published before both
    died: ``online``, the rotator online, its last bearing; the bridge's last will never came.
    The remote answered ``p`` with that bearing and ``RPRT 0`` to moves. Only the station's
    heartbeat (remote/rotator.py rule 1) says a bridge lives."""
    for topic, payload in (
        ("rotor/info", '{"name":"tower","model":"rotorez","azimuth_range":[0,360]}'),
        ("rotor/bridge/state", "online"),
        ("rotor/availability", "online"),
        ("rotor/status", '{"bearing":42.0,"state":"idle","connected":true,"available":true}'),
    ):
        probe.publish(topic, payload, retain=True)
    port = free_port()
    r = Remote(settings(broker, port))  # type: ignore[arg-type]
    r.start()
    try:
        wait_until(lambda: r.view.get("rotor/status") is not None, 5, "the restored status")
        log_from = broker.log.stat().st_size
        assert ask(port, b"p\n") == b"RPRT -5\n"
        assert ask(port, b"P 200 0\n") == b"RPRT -5\n"
        assert remote_published(broker, log_from) == []
        with Heartbeat(probe):  # the station's bridge back: its word counts again
            wait_until(lambda: ask(port, b"p\n") == b"42.00\n0.00\n", 10, "the station heard")
    finally:
        r.stop()


def test_the_remote_logs_what_check_config_would_warn_of_its_console(tmp_path: Path) -> None:
    """Its file has no check-config: a console behind a proxy with no host name listed (a
    rebinding page's failed logins counted with the operator's) was said nowhere."""
    conf = tmp_path / "remote.toml"
    secret = tmp_path / "web-password"
    secret.write_text("correct horse battery\n")
    secret.chmod(0o600)
    conf.write_text(
        f'operator = "DL1ABC"\n[mqtt]\nport = {free_port()}\n'
        f'[web]\nenabled = true\nport = {free_port()}\ntrusted_proxies = ["127.0.0.1"]\n'
        f'password_file = "{secret}"\n'
        f"[[endpoints]]\nrotctld_port = {free_port()}\n"
    )
    argv = [sys.executable, "-m", "bridge", "remote", "-c", str(conf)]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=slow(30), check=False)
    assert done.returncode == 2 and "cannot reach the station's broker" in done.stderr
    assert "WARNING bridge.cli: web.host_names: none listed, with trusted_proxies" in done.stderr


def test_another_operators_lease_is_refused_at_once_whatever_the_stations_clock_says(
    rig: Rig,
) -> None:
    """remote/rotator.py rule 6 on a station whose wall clock is an hour behind the operator's
    (a Raspberry Pi without a clock chip): the lease ends at the time ``R/control`` gives on the
    station's clock. The remote compared it with its own, took G4XYZ's lease for long over and
    answered ``RPRT 0`` to a move the station then refused on its ``R/error`` alone."""
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    rig.app = App(rig.settings, wall=lambda: time.time() - 3600.0)
    rig.app.start()
    rig.ready("tower")
    port = free_port()
    r = Remote(settings(rig.broker, port))  # type: ignore[arg-type]
    r.start()
    other = paho.Client(CallbackAPIVersion.VERSION2, client_id="g4xyz", protocol=paho.MQTTv5)
    other.connect("127.0.0.1", rig.broker.port)
    other.loop_start()
    try:
        other.publish("rotor/control/claim", '{"operator": "G4XYZ", "minutes": 5}', qos=1)
        wait_until(lambda: b"G4XYZ" in (r.view.get("rotor/control") or b""), 10, "the lease")
        assert ask(port, b"P 100 0\n") == b"RPRT -9\n"  # refused at once, as the station does
        other.publish("rotor/control/release", '{"operator": "G4XYZ"}', qos=1)
        wait_until(lambda: b'"holder":null' in (r.view.get("rotor/control") or b""), 10, "free")
        assert ask(port, b"P 100 0\n") == b"RPRT 0\n"  # free: it goes
        rig.arrived("tower", 100)
    finally:
        other.loop_stop()
        other.disconnect()
        r.stop()
