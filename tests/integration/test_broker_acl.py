"""What the broker refuses is said (interfaces/mqtt/client.py rule 11; issue 14, item 9): mosquitto
answered "not authorised" (0x87) to 71 discovery publishes and the bridge logged nothing."""

from __future__ import annotations

import json
import logging
import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from bridge.app import App
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces.mqtt.client import MqttClient
from bridge.settings import MqttSettings
from tests.integration.test_last_word import main_held_at
from tests.support import Probe, free_port
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

GRANTED = ReasonCode(PacketTypes.SUBACK, "Granted QoS 0")
REFUSED = ReasonCode(PacketTypes.SUBACK, "Not authorized")


def _denials(client: MqttClient) -> list[tuple[str, str]]:
    """What the client says it was denied (topic, problem), as it says it."""
    seen: list[tuple[str, str]] = []
    client._on_denied = lambda topic, problem: seen.append((topic, problem))
    return seen


def test_denied_publishes_are_reported_once_each_naming_the_topic(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    # Home Assistant's prefix is not granted
    with acl_rig(tmp_path, "topic readwrite rotor/#\n") as (rig, probe):
        rig.add("tower", "rotorez", emu={"start_az_deg": 20})
        rig.app = App(rig.settings)
        rig.app.start()
        rig.ready("tower")
        bearing = "homeassistant/sensor/rotorbridge_rotor_r_tower/bearing/config"

        def denials() -> list[str]:
            return [r.getMessage() for r in caplog.records if "does not let" in r.getMessage()]

        wait_until(lambda: any(f"publish to {bearing}" in d for d in denials()), 10, "denial")
        info = probe.wait_for("rotor/bridge/info", lambda m: bearing.encode() in m.payload, 10)
        assert any(bearing in p for p in json.loads(info.payload)["problems"])

        def status_says_so(m: Any) -> bool:
            doc = json.loads(m.payload)
            return "does not let the bridge" in (doc.get("last_error") or "")

        probe.wait_for("rotor/status", status_says_so, 10)  # Home Assistant's last-error sensor
        rig.app.client.republish_retained()  # the configs once more: no second report
        rig.probe.publish("rotor/target", "40")  # a round trip through the broker after it
        rig.probe.wait_value("rotor/state", "moving", 10)
        assert len(denials()) == len(set(denials()))  # once per topic


def test_a_denied_subscription_is_reported_naming_the_topic(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Brokers that refuse a subscription say so in the SUBACK (mosquitto 2.0.11 does not: it
    accepts the subscription and delivers nothing, which no client can tell from silence)."""
    client = MqttClient(
        MqttSettings(), will_topic="rotor/bridge/state", subscriptions=[], on_message=print
    )
    seen = _denials(client)
    client._sub_filters[7] = ["rotor/target", "rotor/stop"]
    granted, refused = GRANTED, REFUSED
    client._on_subscribe(client._client, None, 7, [granted, refused], None)
    assert [t for t, _p in seen] == ["rotor/stop"]
    assert "subscribe to rotor/stop: Not authorized" in seen[0][1]
    assert client.problems == [seen[0][1]]


def test_with_discovery_off_a_denied_config_filter_is_said_once_and_is_no_problem(
    rig: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    """Discovery turned off reads Home Assistant's config topics to clear an earlier run's
    (homeassistant/publisher.py rule 6). A broker whose ACL keeps the bridge out of that prefix
    (why its owner turned discovery off) and says so in the SUBACK put "not authorised" on
    B/bridge/info and every rotator's last error, and the command topics did not count as
    subscribed (express.py rule 11): said once in the log now, nothing else
    (interfaces/mqtt/client.py rule 17)."""
    rig.add("tower")
    rig.sections["homeassistant"] = {"enabled": False}
    app = App(rig.settings)
    client = app.client
    config_filter = "homeassistant/+/+/+/config"
    seen = _denials(client)
    granted, refused = GRANTED, REFUSED
    caplog.set_level(logging.INFO)
    for mid in (7, 8):  # (a second connection's SUBACK: said once)
        client._command_mid = mid
        client._sub_filters[mid] = ["rotor/target", config_filter]
        client._on_subscribe(client._client, None, mid, [granted, refused], None)
    assert seen == [] and client.problems == []
    assert client._subscribed_since is not None
    said = [r.getMessage() for r in caplog.records if config_filter in r.getMessage()]
    assert len(said) == 1 and "are not cleared" in said[0], said
    client._sub_filters[9] = ["rotor/target", "rotor/stop"]  # (any other topic: a problem)
    client._on_subscribe(client._client, None, 9, [granted, refused], None)
    assert [t for t, _p in seen] == ["rotor/stop"]


def test_a_denied_filter_read_only_to_refuse_a_groups_other_commands_is_no_problem(
    rig: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    """service.py rule 10 reads a rotator's other command topics under a group's root
    (``G/lock``, ``G/option/+``, ...) only to refuse what comes there. An ACL that grants the
    group its target and stop (the group's commands until then) and says so in the SUBACK put
    "not authorised" on B/bridge/info and every rotator's last error, and the command topics
    did not count as subscribed (express.py rule 11): said once in the log now, nothing else
    (interfaces/mqtt/client.py rule 17)."""
    rig.add("upper")
    rig.add("lower")
    rig.sections["groups"] = [{"id": "stack", "rotators": ["upper", "lower"]}]
    client = App(rig.settings).client
    seen = _denials(client)
    granted, refused = GRANTED, REFUSED
    caplog.set_level(logging.INFO)
    denied = ["rotor/stack/lock", "rotor/stack/option/+", "rotor/stack/track"]
    assert all(t in client._subscriptions for t in denied)
    client._command_mid = 7
    client._sub_filters[7] = ["rotor/stack/target", "rotor/stack/stop", *denied]
    client._on_subscribe(client._client, None, 7, [granted, granted, *[refused] * 3], None)
    assert seen == [] and client.problems == []
    assert client._subscribed_since is not None
    said = [r.getMessage() for r in caplog.records if "rotor/stack/lock" in r.getMessage()]
    assert len(said) == 1 and "not refused on rotor/stack/error" in said[0], said


def test_reporting_a_refusal_never_deadlocks_a_thread_that_publishes(tmp_path: Path) -> None:
    """Review finding: paho calls on_publish holding its own mutex; the report published (our
    lock), while the serial-lines thread held our lock publishing an error event and waited
    for paho's mutex: both hung for good on the first refused publish, and no stop went out."""
    acl = tmp_path / "acl"
    acl.write_text("topic readwrite ok/#\n")
    conf = f"allow_anonymous true\nacl_file {acl}\nuser root"
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf)
    broker.start()
    client: MqttClient | None = None

    def denied(topic: str, problem: str) -> None:
        assert client is not None
        client.publish_retained("ok/info", problem[:60])

    client = MqttClient(
        MqttSettings(host="127.0.0.1", port=broker.port),
        will_topic="ok/online",
        subscriptions=[],
        on_message=lambda *a: None,
        on_denied=denied,
    )
    try:
        client.start()
        assert client.connected.wait(slow(5))
        done = threading.Event()

        def lines() -> None:
            assert client is not None
            for i in range(5000):
                client.publish_event(f"no/{i}/error", b"x")  # each one refused
            done.set()

        threading.Thread(target=lines, daemon=True).start()
        assert done.wait(slow(30)), "the publishing thread hung"
        wait_until(lambda: len(client.problems) >= 100, 10, "refusals reported")
    finally:
        client.stop()
        broker.stop()


@contextmanager
def acl_rig(tmp_path: Path, acl_text: str) -> Iterator[tuple[Rig, Probe]]:
    """A rig on a mosquitto of its own with ``acl_text`` as its ACL file."""
    acl = tmp_path / "acl"
    acl.write_text(acl_text)
    # started as root, mosquitto would become user "mosquitto", who cannot read pytest's tmp
    conf = f"allow_anonymous true\nacl_file {acl}\nuser root"
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf)
    broker.start()
    probe = Probe(broker.port, "rotor/#")
    rig = Rig(tmp_path, broker, probe)
    try:
        yield rig, probe
    finally:
        rig.close()
        probe.close()
        broker.stop()


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_markers_the_acl_drops_are_known_from_the_first_connection_and_a_stop_still_holds(
    tmp_path: Path, protocol: str
) -> None:
    """lastword.py rule 7, client.py rule 16: mosquitto grants the subscription to
    B/bridge/fence and drops the bridge's markers without a word; the bridge knows it from its
    probe on connecting (B/bridge/info says so before any stop), and a lane's stop still
    holds the targets published before it until the main connection reads its own copy of
    the stop; the next target turns the rotor. (Under MQTT 5 mosquitto refuses the probe's
    publish in its PUBACK; under MQTT 3.1.1 only the probe's order says so.)"""
    acl = "topic readwrite rotor/#\ntopic deny rotor/bridge/fence\n"
    with acl_rig(tmp_path, acl) as (rig, probe):
        rig.mqtt_extra = {"protocol": protocol}
        emu = rig.add("tower", "rotorez", emu={"start_az_deg": 20, "speed_deg_s": 20.0})
        app = rig.start()
        info = probe.wait_for("rotor/bridge/info", lambda m: b"rotor/bridge/fence" in m.payload)
        (said,) = [p for p in json.loads(info.payload)["problems"] if "bridge/fence" in p]
        assert ("publish to" if protocol == "5" else "read back") in said
        rig.ready("tower")
        wait_until(app.lane.connected.is_set, 10, "the lane is up")
        with main_held_at(app, "rotor/target", b"60") as held:
            probe.publish("rotor/target", "60")
            wait_until(held.is_set, 10, "the main connection is held")
            probe.publish("rotor/stop", "")
            wait_until(lambda: app.mqtt._word.holding, 10, "the lane's stop holds")
        wait_until(lambda: not app.mqtt._word.holding, 10, "its main copy ended the hold")
        assert not [f for f in emu.frames(*BEARING_OUTCOMES) if b"60" in f.data]
        probe.publish("rotor/target", "200")
        emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 200) <= 3, 30)


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_the_fence_problem_leaves_bridge_info_when_the_acl_lets_it_on_a_later_connect(
    tmp_path: Path, protocol: str
) -> None:
    """client.py rule 16: one denied probe was said on B/bridge/info for ever. The probe is
    judged on every connect: once the broker's ACL lets the fence through, the next
    connection's probe comes back and the problem is gone. The markers go out all along: they
    come back on the hello topic (lastword.py rule 7)."""
    acl = "topic readwrite rotor/#\ntopic deny rotor/bridge/fence\n"
    with acl_rig(tmp_path, acl) as (rig, probe):
        rig.mqtt_extra = {"protocol": protocol}
        rig.add("tower", "rotorez", emu={"start_az_deg": 20})
        app = rig.start()
        probe.wait_for("rotor/bridge/info", lambda m: b"rotor/bridge/fence" in m.payload)
        assert app.mqtt._word.markers
        (tmp_path / "acl").write_text("topic readwrite rotor/#\n")
        before = time.monotonic()
        rig.broker.restart()
        probe.wait_for(
            "rotor/bridge/info", lambda m: b"rotor/bridge/fence" not in m.payload, 30, before
        )
        assert app.mqtt._word.markers


def test_markers_stop_only_when_neither_copy_can_come_back_and_go_out_again_once_one_can(
    tmp_path: Path,
) -> None:
    """lastword.py rule 7, client.py rule 16 (MQTT 5: the probe's PUBACK says the fence is
    denied; under MQTT 3.1.1 only the hello, here denied too, could say it): with the fence
    and the hello topic both denied no marker could come back, and none goes out once the
    first look's time is up; a later connection whose hello comes back sends them again."""
    acl = "topic readwrite rotor/#\ntopic deny rotor/bridge/fence\ntopic deny rotor/bridge/hello\n"
    with acl_rig(tmp_path, acl) as (rig, _probe):
        rig.mqtt_extra = {"protocol": "5"}
        rig.add("tower", "rotorez", emu={"start_az_deg": 20})
        app = rig.start()
        wait_until(lambda: not app.mqtt._word.markers, 20, "the markers off")
        (tmp_path / "acl").write_text("topic readwrite rotor/#\ntopic deny rotor/bridge/fence\n")
        rig.broker.restart()
        wait_until(lambda: app.mqtt._word.markers, 30, "the markers on again")


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_with_the_fence_topic_denied_a_target_published_before_a_rotctld_stop_never_turns_it(
    tmp_path: Path, protocol: str
) -> None:
    """lastword.py rule 7 (an attack pass): with B/bridge/fence denied by the broker's ACL the
    bridge sent no marker, so rotctld's S fenced nothing, and a target published on MQTT just
    before it, read by the main connection after it, turned the rotor after the STOP. The
    markers' copies on B/bridge/hello come back: that target is refused, the next one obeyed."""
    acl = "topic readwrite rotor/#\ntopic deny rotor/bridge/fence\n"
    with acl_rig(tmp_path, acl) as (rig, probe):
        rig.mqtt_extra = {"protocol": protocol}
        port = free_port()
        emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0}, rotctld_port=port)
        app = rig.start()
        probe.wait_for("rotor/bridge/info", lambda m: b"rotor/bridge/fence" in m.payload)
        rig.ready("tower")
        probe.publish("rotor/target", "200")
        emu.wait_for(lambda s: s.is_moving, 10)
        t = time.monotonic()
        with main_held_at(app, "rotor/target", b"300") as held:
            probe.publish("rotor/target", "300")  # published first, read last
            wait_until(held.is_set, 10, "the main connection held on the target")
            with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
                s.sendall(b"S\n")
                assert s.recv(100) == b"RPRT 0\n"
            emu.wait_for(lambda s: not s.is_moving, 10)
        err = probe.wait_for("rotor/error", lambda m: b"300" in m.payload, 10, after=t)
        assert "published before a STOP or lock ON" in json.loads(err.payload)["message"]
        probe.publish("rotor/target", "60")  # (after the S's marker, queued before that error)
        rig.arrived("tower", 60)
        assert not [f for f in emu.frames(*BEARING_OUTCOMES) if b"300" in f.data]


def denies_fence_now(probe: Probe) -> bool:
    """Whether the broker drops what is published on rotor/bridge/fence now: a word published
    there, then one on rotor/bridge/hello (one client, one QoS: one order), and the second
    comes back without the first (the probe is under the same ACL as the bridge)."""
    word = f"acl-{time.monotonic_ns()}".encode()
    mark = probe.mark()
    probe.publish("rotor/bridge/fence", word)
    probe.publish("rotor/bridge/hello", word)
    probe.wait_for("rotor/bridge/hello", lambda m: m.payload == word)
    return not [m for m in probe.messages[mark:] if m.payload == word and "fence" in m.topic]


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_a_fence_acl_reloaded_mid_connection_leaves_mqtt_targets_obeyed_after_a_rotctld_stop(
    tmp_path: Path, protocol: str
) -> None:
    """lastword.py rule 7: mosquitto reloads its ACL file on SIGHUP and keeps the connections,
    so the bridge's probe (on connecting) never learns that B/bridge/fence is now denied. After
    rotctld's S, every MQTT target was refused as "published before a STOP ... that another
    interface carried out first" for as long as the connection lasted: no marker came back to
    end the fence. Every marker also goes on B/bridge/hello, which the main connection reads
    back: the target published before the S is still refused, the one after it turns the
    rotor."""
    with acl_rig(tmp_path, "topic readwrite rotor/#\n") as (rig, probe):
        rig.mqtt_extra = {"protocol": protocol}
        port = free_port()
        emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0}, rotctld_port=port)
        app = rig.start()
        rig.ready("tower")
        (tmp_path / "acl").write_text("topic readwrite rotor/#\ntopic deny rotor/bridge/fence\n")
        rig.broker.reload()
        wait_until(lambda: denies_fence_now(probe), 10, "the broker drops the fence topic")
        probe.publish("rotor/target", "200")
        emu.wait_for(lambda s: s.is_moving, 10)
        t = time.monotonic()
        with main_held_at(app, "rotor/target", b"300") as held:
            probe.publish("rotor/target", "300")  # published first, read last
            wait_until(held.is_set, 10, "the main connection held on the target")
            with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
                s.sendall(b"S\n")
                assert s.recv(100) == b"RPRT 0\n"
            emu.wait_for(lambda s: not s.is_moving, 10)
        err = probe.wait_for("rotor/error", lambda m: b"300" in m.payload, 10, after=t)
        assert "published before a STOP or lock ON" in json.loads(err.payload)["message"]
        # (the S's marker was queued before that error on the bridge's connection: this
        # target comes after it)
        probe.publish("rotor/target", "60")
        rig.arrived("tower", 60)
        assert not [f for f in emu.frames(*BEARING_OUTCOMES) if b"300" in f.data]
        assert not [m for m in probe.messages if m.topic == "rotor/bridge/fence" and m.t >= t]


class Watched:
    """A lock that notes when a thread has to wait for it."""

    def __init__(self) -> None:
        self.lock, self.waited = threading.Lock(), threading.Event()

    def __enter__(self) -> None:
        if not self.lock.acquire(blocking=False):
            self.waited.set()
            self.lock.acquire()

    def __exit__(self, *exc: object) -> None:
        self.lock.release()


def test_two_problems_said_at_once_from_two_threads_are_both_on_bridge_info(rig: Rig) -> None:
    """App rule 4 (review finding): each thread changed the list, then published the list it had
    built, each on its own: a thread that built its payload before another's change published
    it after, and the broker kept a list without the other's problem. Forced here: the second
    problem is said while the first one's publish is under way."""
    rig.add("tower", "rotorez")
    app = rig.start()
    rig.ready("tower")
    info = "rotor/bridge/info"
    first, second = "tower: the first problem", "tower: the second problem"
    publish, watched = app.client.publish_retained, Watched()
    app._problems_lock = watched  # type: ignore[assignment]
    second_out, both = threading.Event(), threading.Thread(target=app._info, args=(second, True))

    def publishing(topic: str, payload: str | bytes, **kw: Any) -> None:
        text = payload if isinstance(payload, str) else payload.decode()
        if topic == info and first in text and second not in text:  # the first one's publish
            both.start()  # the second problem said now: its list goes out before, or it waits
            wait_until(lambda: second_out.is_set() or watched.waited.is_set(), 10, "the second")
        publish(topic, payload, **kw)
        if topic == info and second in text:
            second_out.set()

    app.client.publish_retained = publishing  # type: ignore[method-assign]
    start = rig.probe.mark()
    app._info(first, True)
    both.join(slow(10))
    assert not both.is_alive()
    for said in ([first], [first, second]):  # both lists reached the broker (in either order)
        rig.probe.wait(
            lambda m, s=said: m.topic == info and json.loads(m.payload)["problems"] == s,
            10,
            f"{said} on {info}",
            start,
        )
    assert json.loads(rig.retained()[info])["problems"] == [first, second]


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_a_hello_back_after_the_look_s_time_lets_a_rotctld_stop_fence_with_the_fence_denied(
    tmp_path: Path, protocol: str
) -> None:
    """client.py rule 16, lastword.py rule 7 (an attack pass): the main connection's hello
    came back after the first look's 5 s (a broker slow to send the retained messages that
    come before it; here the main connection held at one of them), the fence topic denied:
    the markers were said lost for the connection, although their copies on B/bridge/hello
    come back, and rotctld's S fenced nothing: a target published on MQTT before it and read
    after it turned the rotor. The late hello says the markers come back: that target is
    refused. (Under MQTT 3.1.1 the markers stayed on, but B/bridge/info never named the
    denied fence topic: only the hello back before the probe says it there.)"""
    acl = "topic readwrite rotor/#\ntopic deny rotor/bridge/fence\n"
    with acl_rig(tmp_path, acl) as (rig, probe):
        rig.mqtt_extra = {"protocol": protocol}
        port = free_port()
        emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0}, rotctld_port=port)
        probe.publish("rotor/target", "slow broker", retain=True)  # (bad input: moves nothing)
        app = rig.app = App(rig.settings)
        with main_held_at(app, "rotor/target", b"slow broker") as held:
            app.start()
            wait_until(held.is_set, 10, "the main connection held before its hello")
            wait_until(lambda: app.client._look_lost, 20, "the first look's time up")
        probe.publish("rotor/target", "", retain=True)
        probe.wait_for("rotor/bridge/info", lambda m: b"rotor/bridge/fence" in m.payload)
        rig.ready("tower")
        probe.publish("rotor/target", "200")
        emu.wait_for(lambda s: s.is_moving, 10)
        t = time.monotonic()
        with main_held_at(app, "rotor/target", b"300") as held:
            probe.publish("rotor/target", "300")  # published first, read last
            wait_until(held.is_set, 10, "the main connection held on the target")
            with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
                s.sendall(b"S\n")
                assert s.recv(100) == b"RPRT 0\n"
            emu.wait_for(lambda s: not s.is_moving, 10)
        err = probe.wait_for("rotor/error", lambda m: b"300" in m.payload, 10, after=t)
        assert "published before a STOP or lock ON" in json.loads(err.payload)["message"]
        probe.publish("rotor/target", "60")
        rig.arrived("tower", 60)
        assert not [f for f in emu.frames(*BEARING_OUTCOMES) if b"300" in f.data]
