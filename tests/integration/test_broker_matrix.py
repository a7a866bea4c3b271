"""The broker matrix (docs/brokers.md): what a station needs of its broker, checked end to end
against each broker the tests can start, with the bridge's default ``mqtt.protocol`` ("auto")
unless the case forces one: mosquitto on MQTT 5, mosquitto forced to 3.1.1, NATS and aedes
0.46 as Node-RED embeds it (both MQTT 3.1.1 only: "auto" steps down; aedes also reorders a QoS 0
message before the QoS 1 one sent right before it, which once made the fence look denied).
Each case: the protocol said at start, a target turns the rotor, a STOP while turning stops it,
the retained state for a subscriber that comes late, the last will, the fence markers
(lastword.py rule 7), an MQTT target after rotctld's stop (the fence of lastword.py rule 11
ends on this broker), a lock ON the broker keeps across a restart on a new state file
(runtime/kept.py rule 10), under 3.1.1 a flood of targets without a false "another client
published" while a real stranger is still put back and said, and a second stray soon after
the first put back too.

Real parts: the broker, the bridge (App, or its own process for the last will) and an emulated
Rotor-EZ on a pty (tests/support/rig.py); the probe speaks MQTT 3.1.1, as every broker does.
"""

from __future__ import annotations

import json
import logging
import os
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.interfaces.mqtt.client import SETTLE_AFTER_CONNECT_S
from bridge.interfaces.mqtt.owned import FOREIGN_FIX_S
from tests.support import Probe, free_port, retained_snapshot, wait_until
from tests.support.brokers import Aedes, Amqtt, Nats, RabbitMq, find_aedes, find_nats
from tests.support.console import ConsoleClient, web_section
from tests.support.mosquitto import BrokerError, Mosquitto
from tests.support.rig import Rig
from tests.support.waiting import slow

BROKERS = ["mosquitto-5", "mosquitto-3.1.1", "nats", "aedes"]
# ./tests/run brokers adds the brokers that take longer to install and start (docs/brokers.md)
if os.environ.get("ROTOR_TEST_BROKERS") == "all":
    BROKERS += ["rabbitmq", "amqtt"]
STEPS_DOWN = {"nats", "aedes"}  # MQTT 3.1.1 only: "auto" steps down on their refusal
CLOSES_V5 = {"rabbitmq", "amqtt"}  # ... and these close MQTT 5: "auto" asks, then steps down
STRANGER = "another client published"


@pytest.fixture(params=BROKERS)
def kind(request: pytest.FixtureRequest) -> str:
    if request.param == "nats" and find_nats() is None:
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    if request.param == "aedes" and find_aedes() is None:
        pytest.fail("aedes is not installed (tests/run installs it: npm ci in tests/brokers/aedes)")
    return str(request.param)


@pytest.fixture
def station(kind: str, tmp_path: Path) -> Iterator[Rig]:
    others = {"nats": Nats, "aedes": Aedes, "rabbitmq": RabbitMq, "amqtt": Amqtt}
    broker: Mosquitto | Nats | Aedes | RabbitMq | Amqtt = (
        others[kind](tmp_path / kind) if kind in others else Mosquitto(tmp_path / "mosquitto")
    )
    broker.start()
    probe = Probe(broker.port)
    try:
        with Rig(tmp_path, broker, probe) as rig:
            if kind == "mosquitto-3.1.1":
                rig.mqtt_extra = {"protocol": "3.1.1"}
            if kind == "amqtt":  # it never answers an MQTT 5 CONNECT with a will: two CONNACK
                rig.ready_s = 60.0  # timeouts and the MQTT 3.1.1 trial before the step-down
            yield rig
    finally:
        probe.close()
        broker.stop()


@pytest.mark.parametrize("other", ["nats", "aedes"])
def test_a_broker_whose_port_another_program_holds_is_not_taken_for_started(
    other: str, tmp_path: Path
) -> None:
    """Another program listening on the port answered before the broker had tried to bind it:
    the start returned, the broker exited, and the station reached the other program's broker
    (under two suites at once, another test's). That start fails now, and ``start`` takes
    another port, as when the broker's own bind fails."""
    if (find_nats() if other == "nats" else find_aedes()) is None:
        pytest.fail(f"{other} is not installed (tests/run installs it)")
    broker = Nats(tmp_path / other) if other == "nats" else Aedes(tmp_path / other)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", broker.port))
        taken.listen()
        try:
            with pytest.raises(BrokerError, match="exited"):
                broker._start(slow(broker.start_s))
        finally:
            broker.stop()
        broker.start()
        try:
            assert broker.port != taken.getsockname()[1]
        finally:
            broker.stop()


def said(caplog: pytest.LogCaptureFixture, words: str) -> list[str]:
    return [r.getMessage() for r in caplog.records if words in r.getMessage()]


def test_the_bridge_says_which_protocol_it_speaks_and_what_that_means(
    kind: str, station: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.INFO)
    station.add("tower")
    station.start()
    station.ready("tower")
    connected = said(caplog, "connected to MQTT broker (")
    losses = said(caplog, "carried out like any other")
    if kind == "mosquitto-5":
        assert connected and all("(MQTT 5)" in line for line in connected), connected
        assert losses == []
    else:
        assert connected and all("(MQTT 3.1.1)" in line for line in connected), connected
        assert len(losses) == 1, losses  # one warning, at start
    if kind in STEPS_DOWN | CLOSES_V5:
        (line,) = said(caplog, "using MQTT 3.1.1 from now on")
        if kind in CLOSES_V5:
            assert "closed MQTT 5 connections before answering them and accepted" in line
        else:
            assert 'refused MQTT 5 ("Unsupported protocol version")' in line
        # the step-down is on B/bridge/info while it lasts, for Home Assistant and a dashboard
        info = station.probe.wait_for("rotor/bridge/info", lambda m: "MQTT 3.1.1" in m.text)
        (problem,) = json.loads(info.payload)["problems"]
        assert "a retained target moves the rotor once" in problem
    else:  # MQTT 5, or 3.1.1 chosen by hand: nothing stepped down
        assert json.loads(station.retained()["rotor/bridge/info"])["problems"] == []
    assert said(caplog, "refused the connection") == []


def test_a_target_turns_the_rotor_and_a_stop_while_turning_stops_it(station: Rig) -> None:
    station.express = True  # the stop express's own connection, on each broker (rig.py)
    emu = station.add("tower", emu={"start_az_deg": 0, "speed_deg_s": 20})
    station.start()
    station.ready("tower")
    station.probe.publish("rotor/target", "40")
    emu.wait_for(lambda s: abs(s.az_deg - 40) <= 3 and not s.is_moving, 20)
    station.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 60)
    station.probe.publish("rotor/stop", "STOP")
    stopped = emu.wait_for(lambda s: not s.is_moving, 5)
    assert stopped.az_deg < 250
    # the fence markers (lastword.py rule 7): the stop's marker came back through this broker,
    # and the bridge reports no problem with it
    station.probe.wait_for("rotor/bridge/fence", lambda m: not m.payload.startswith(b"probe "))
    info = json.loads(station.probe.wait_for("rotor/bridge/info").payload)
    assert not [p for p in info.get("problems", []) if "fence" in p], info


def test_a_late_subscriber_gets_the_retained_state(kind: str, station: Rig) -> None:
    emu = station.add("tower", emu={"start_az_deg": 0})
    station.start()
    station.ready("tower")
    station.probe.publish("rotor/target", "90")
    emu.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 20)
    # RabbitMQ replays retained messages to exact-topic subscriptions only (docs/brokers.md)
    wanted = ["rotor/state", "rotor/bridge/state", "rotor/lock/state", "rotor/status"]
    subscription = "|".join(wanted) if kind == "rabbitmq" else "rotor/#"

    def settled() -> dict[str, bytes] | None:
        snap = retained_snapshot(station.broker.port, subscription)
        return snap if snap.get("rotor/state") == b"idle" else None

    snap = wait_until(settled, 10, "a new subscriber gets rotor/state idle")
    assert snap["rotor/bridge/state"] == b"online"
    assert snap["rotor/lock/state"] == b"OFF"
    assert abs(json.loads(snap["rotor/status"])["bearing"] - 90) <= 3


def test_the_last_will_marks_a_killed_bridge_offline(station: Rig) -> None:
    station.add("tower")
    bridge = station.start_process()
    station.probe.wait_value("rotor/bridge/state", "online", timeout_s=max(20, station.ready_s))
    t = time.monotonic()
    bridge.kill()
    station.probe.wait_for("rotor/bridge/state", lambda m: m.text == "offline", 20, after=t)
    # a new subscriber is handed the will as the retained state (aedes hands retained messages
    # from its store after the SUBACK, so its arrival is waited for, not a round trip's end)
    late = Probe(station.broker.port, "rotor/bridge/state")
    try:
        got = late.wait_for("rotor/bridge/state", lambda m: m.retain, 10)
        assert got.payload == b"offline"
    finally:
        late.close()


def test_a_flood_raises_no_false_alarm_and_a_real_stranger_is_still_put_back(
    kind: str, station: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    """Under 3.1.1 the bridge hears its own messages; behind a flood of targets read first they
    come back late, and none may pass for a stranger's (owned.py rule 10)."""
    emu = station.add("tower", emu={"start_az_deg": 0, "speed_deg_s": 20})
    app = station.start()
    station.ready("tower")
    synced = threading.Event()
    on_main = app.client._handler

    def main(topic: str, payload: bytes, *rest: Any) -> None:
        on_main(topic, payload, *rest)
        if topic == "rotor/target" and payload == b"sync":
            synced.set()

    app.client._handler = main
    flood = Probe(station.broker.port, "", max_inflight=1000)
    try:
        for i in range(5000):
            flood.client.publish("rotor/target", str(10 + i % 300), qos=0)
        flood.client.publish("rotor/stop", "STOP", qos=1).wait_for_publish(30)
    finally:
        flood.close()
    # a sync round trip through the bridge: every target before it has been read (read, not
    # said on R/error: the flood's targets read behind the lane's STOP are refused as older,
    # lastword.py rule 2, and use up its budget)
    station.probe.publish("rotor/target", "sync")
    wait_until(synced.is_set, 60, "the main connection read the sync")
    assert said(caplog, STRANGER) == []
    emu.wait_for(lambda s: not s.is_moving, 30)  # the STOP behind the flood held
    # a stranger's value on a topic of the bridge's own is still put back, and said
    t = time.monotonic()
    station.probe.publish("rotor/lock/state", "ON", retain=True)
    station.probe.wait_for("rotor/lock/state", lambda m: m.text == "OFF", 10, after=t)
    wait_until(lambda: said(caplog, STRANGER), 60, "the stranger said")  # behind the echoes
    assert len(said(caplog, STRANGER)) == 1


def test_a_second_stray_soon_after_the_first_is_put_back_too(kind: str, station: Rig) -> None:
    """owned.py rule 10: a live stray within FOREIGN_FIX_S of a put-back is put back when the
    interval is over, and a value the broker held is not owed; the retain flag tells them apart,
    which needs each broker to clear it on a live message (MQTT 3.1.1) or to honour
    retain-as-published off (MQTT 5)."""
    station.add("tower", emu={"start_az_deg": 20})
    app = station.start()
    station.ready("tower")
    wait_until(
        lambda: time.monotonic() - app.client.connected_at > SETTLE_AFTER_CONNECT_S, 5, "settled"
    )

    def held() -> bytes | None:
        return retained_snapshot(station.broker.port, "rotor/lock/#").get("rotor/lock/state")

    station.probe.publish("rotor/lock/state", "ON", retain=True)
    wait_until(lambda: held() == b"OFF", 10, "the first stray put back")
    station.probe.publish("rotor/lock/state", "ON", retain=True)  # within the interval
    station.probe.caught_up()
    wait_until(lambda: held() == b"OFF", slow(FOREIGN_FIX_S + 4), "the second stray put back")


def test_its_own_last_will_at_a_broker_shutdown_is_no_strangers(
    kind: str, station: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    """A broker that shuts down publishes the wills of its clients, the bridge's too; under
    3.1.1 the bridge hears it, and it is its own (owned.py rule 10)."""
    station.add("tower")
    app = station.start()
    station.ready("tower")
    station.broker.stop()
    wait_until(lambda: not app.client.connected.is_set(), 10, "the bridge saw the broker go")
    wait_until(lambda: said(caplog, "disconnected from MQTT broker"), 10, "the disconnect said")
    assert said(caplog, STRANGER) == []


def test_home_assistant_gets_every_config_again_on_its_birth(station: Rig) -> None:
    """After Home Assistant restarts, its ``homeassistant/#`` subscription gets no retained
    config on RabbitMQ (exact topics only): the bridge sends every config again on the birth
    message, on every broker."""
    ha = Probe(station.broker.port, "homeassistant/#")  # live, before the bridge starts
    try:
        station.add("tower")
        app = station.start()
        station.ready("tower")
        assert app.discovery is not None
        known = set(app.discovery._current)  # every config the bridge has published
        assert len(known) >= 10, known
        t = time.monotonic()
        station.probe.publish("homeassistant/status", "online")  # the birth (not retained)
        for topic in sorted(known):
            ha.wait_for(topic, lambda m: bool(m.payload), 30, after=t)
    finally:
        ha.close()


def test_the_lock_refuses_a_target_and_a_stop_from_a_second_client_ends_a_flood(
    station: Rig,
) -> None:
    """The lock holds on every broker; 5,000 targets from one client and then a STOP from
    another: the rotor stops and does not start again."""
    emu = station.add("tower", emu={"start_az_deg": 0, "speed_deg_s": 20})
    station.start()
    station.ready("tower")
    t = time.monotonic()
    station.probe.publish("rotor/lock", "ON")
    station.probe.wait_value("rotor/lock/state", "ON", after=t)
    station.probe.publish("rotor/target", "120")
    refused = station.probe.wait_for("rotor/error", lambda m: b"lock" in m.payload, after=t)
    assert json.loads(refused.payload)["kind"] == "refused"
    assert not emu.state().is_moving
    station.probe.publish("rotor/lock", "OFF")
    station.probe.wait_value("rotor/lock/state", "OFF", after=t)
    flood = Probe(station.broker.port, "", max_inflight=1000)
    try:
        for i in range(5000):
            flood.client.publish("rotor/target", str(10 + i % 300), qos=0)
        emu.wait_for(lambda s: s.is_moving, 30)
        station.probe.publish("rotor/stop", "STOP")  # the second client
        emu.wait_for(lambda s: not s.is_moving, 30)
        stopped = emu.state().az_deg
        # the flood's rest, read after the STOP, must not start the rotor again: a sync round
        # trip from the flooding client proves the bridge has read all of it
        t = time.monotonic()
        flood.client.publish("rotor/target", "sync", qos=1).wait_for_publish(30)
        station.probe.wait_for("rotor/error", lambda m: b"sync" in m.payload, 60, after=t)
    finally:
        flood.close()
    assert emu.state().az_deg == stopped and not emu.state().is_moving


def test_a_broker_restart_gets_every_retained_value_back(kind: str, station: Rig) -> None:
    """A broker restarted (with its store wiped where it keeps none): the bridge publishes its
    state again, and a new subscriber finds it."""
    station.add("tower")
    station.start()
    station.ready("tower")
    station.broker.restart()
    wanted = ["rotor/availability", "rotor/bridge/state", "rotor/lock/state", "rotor/status"]

    def back() -> dict[str, bytes] | None:
        snap = retained_snapshot(station.broker.port, "|".join(wanted))
        return snap if all(t in snap for t in wanted) else None

    snap = wait_until(back, max(30, station.ready_s), "the retained state after the restart")
    assert snap["rotor/bridge/state"] == b"online"
    assert snap["rotor/availability"] == b"online"


def test_an_mqtt_target_after_a_rotctld_stop_turns_the_rotor_once_the_marker_is_back(
    station: Rig,
) -> None:
    """lastword.py rule 11: rotctld's ``S`` fences the rotator's MQTT moves until the marker the
    bridge publishes on its main connection comes back through the broker. A fence that never
    ended on a broker (one that does not hand the bridge its own messages, or MQTT 3.1.1, where
    it hears them all) would refuse every MQTT target from then on."""
    port = free_port()
    emu = station.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0}, rotctld_port=port)
    station.start()
    station.ready("tower")
    station.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 30, 20)
    t = time.monotonic()
    with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
        s.sendall(b"S\n")
        assert s.recv(100) == b"RPRT 0\n"
    emu.wait_for(lambda s: not s.is_moving, 10)
    # the fence's marker has passed the broker: what is published now comes after it
    station.probe.wait_for(
        "rotor/bridge/fence", lambda m: not m.payload.startswith(b"probe "), 20, after=t
    )
    t = time.monotonic()
    station.probe.publish("rotor/target", "60")
    station.arrived("tower", 60)
    refusals = [m.text for m in station.probe.on("rotor/error") if m.t >= t]
    assert refusals == []


def test_an_mqtt_lock_off_after_the_consoles_lock_on_unlocks_once_the_marker_is_back(
    station: Rig,
) -> None:
    """lastword.py rule 11 for the lock: the console's lock ON fences the main connection's
    lock OFF until its marker comes back through the broker; a lock OFF published after that
    is the last word on every broker, and unlocks."""
    web = station.sections["web"] = web_section()
    station.add("tower", emu={"start_az_deg": 10})
    app = station.start()
    station.ready("tower")
    console = ConsoleClient(web["port"])
    console.session()
    t = time.monotonic()
    assert console.command("tower", command="lock", on=True).status == 200
    station.probe.wait_value("rotor/lock/state", "ON", after=t)
    station.probe.wait_for(
        "rotor/bridge/fence", lambda m: not m.payload.startswith(b"probe "), 20, after=t
    )
    t = time.monotonic()
    station.probe.publish("rotor/lock", "OFF")
    station.probe.wait_value("rotor/lock/state", "OFF", after=t)
    assert not app.rotators[0].locked
    assert [m.text for m in station.probe.on("rotor/error") if m.t >= t] == []


def test_a_restart_on_a_new_state_file_keeps_the_lock_the_broker_holds(
    kind: str, station: Rig, tmp_path: Path
) -> None:
    """runtime/kept.py rule 10 on each broker: the lock ON an earlier run left retained on
    ``R/lock/state`` locks a bridge started on a state file that says nothing of the lock
    (interfaces/mqtt/look.py rule 14 hears it during the first look): a broker that hands the
    retained value after the look's hello, or not to the bridge's subscription, would let it
    start unlocked and a target turn a rotor locked for tower work. The ON is not put over with
    OFF (a switch shown OFF), but on aedes, which replays it after the hello (once, below)."""
    emu = station.add("tower", emu={"start_az_deg": 10})
    station.start()
    station.ready("tower")
    t = time.monotonic()
    station.probe.publish("rotor/lock", "ON")
    station.probe.wait_value("rotor/lock/state", "ON", after=t)
    station.stop()
    (tmp_path / "state.json").unlink()  # (a new state file: nothing of this rotator)
    t = station.probe.caught_up()
    app = station.start()
    station.ready("tower", after=t)
    wait_until(lambda: app.rotators[0].locked, 10, "the rotator locked after the restart")

    def shown() -> list[str]:
        return [m.text for m in station.probe.on("rotor/lock/state") if m.t > t]

    # left as the broker holds it (look.py rule 14); aedes replays it after the hello, once
    # the open's OFF went out: then ON once (when the lock is saved), never OFF put back
    if kind == "aedes":
        wait_until(lambda: shown()[-1:] != ["OFF"], 10, "the lock shown ON again")
    station.probe.caught_up()  # (what the bridge said before it locked has reached the probe)
    # (and before that, the look's probe of a witness it heard nothing on yet: an empty message,
    # not retained, neither ON nor OFF: look.py rule 14; on aedes alone when its replay of the
    # ON came in the look's second round, before the bridge said anything of its own)
    aedes = ([], [""], ["OFF", "ON"], ["", "OFF", "ON"])
    assert shown() in aedes if kind == "aedes" else shown() == [], shown()
    held = {"rotor/lock/state": b"ON"}
    if kind == "aedes":  # (it hands a new subscriber its retained messages late too, at times
        # after the snapshot's own round trip: CI on a busy machine read none)
        wait_until(
            lambda: retained_snapshot(station.broker.port, "rotor/lock/state") == held,
            10,
            "aedes holding the lock ON",
        )
    else:
        assert retained_snapshot(station.broker.port, "rotor/lock/state") == held
    t = time.monotonic()
    station.probe.publish("rotor/target", "100")
    refused = station.probe.wait_for("rotor/error", lambda m: b"100" in m.payload, 10, after=t)
    assert b"locked" in refused.payload, refused.payload
    assert abs(emu.state().az_deg - 10) < 3, "a rotor locked before the restart turned"
