"""COLD REVIEW 25 (f68d30a8), finding R25-1, with a real mosquitto: open.

tests/mqtt/test_review25_markers_unread.py is its service-level twin. An administrator reloads
mosquitto's ACL file (SIGHUP: the connections are kept) with a typo that lets the bridge publish
its markers on B/bridge/fence and B/bridge/hello but no longer read them. mosquitto takes every
marker (its PUBACK a success) and delivers none back: it checks a read ACL when it delivers.
A STOP the stop lane carries out first then holds its rotator; the main connection's copy of
the STOP is counted, and the target published right after it waits for a marker that never
comes, for as long as the main connection lives (lastword.py rule 15). (A lock ON then OFF,
left locked as long in the service-level twin, is not tested here: its first form passed in
two of five runs, read before the lane's lock ON was shown at all (the status says ON once
the state writer saved it, kept.py rule 2, 5-17 ms after the hold began); traced, the rotator
stayed locked 30 s in every run, no hold ending but by its marker.)

Asking the broker again does not help (measured with mosquitto 2.0.11, MQTT 5 and 3.1.1, the
last test below): its ACL file is never checked on SUBSCRIBE, so a SUBSCRIBE to the marker
topics again, on the live connection or a new one, is granted (QoS 1) whatever the file says,
and nothing in the answer says the markers are unreadable. The fix that would end these holds
on a timer is what rule 5 forbids; these tests stay xfail until the broker can be made to say
it.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge.app import App
from tests.integration.test_broker_acl import acl_rig
from tests.integration.test_last_word import main_held_at, tower
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import SYNC_PREFIX
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

FENCE, HELLO = "rotor/bridge/fence", "rotor/bridge/hello"
ALLOWED = f"topic readwrite rotor/#\ntopic readwrite {SYNC_PREFIX}#\n"
# the typo: every topic as before but for the two marker topics, which may be published only
# (mosquitto grants an access if any line matching the topic grants it, so none may match them)
READ_DENIED = (
    "topic readwrite rotor/+\n"  # the commands, the bridge's state and events
    "topic readwrite rotor/+/+/+/#\n"  # B/bridge/fence/lane, ... (not rotor/+/+/#: "#" matches
    # its parent level too)
    "topic readwrite rotor/lock/state\ntopic readwrite rotor/control/#\n"
    "topic readwrite rotor/bridge/info\ntopic readwrite rotor/bridge/state\n"
    "topic readwrite rotor/bridge/heartbeat\n"
    f"topic write {FENCE}\ntopic write {HELLO}\n"
    f"topic readwrite {SYNC_PREFIX}#\n"
)
OPEN_REASON = (
    "review 25 R25-1, open: mosquitto takes the markers and delivers none back (a read ACL "
    "reloaded under the live connection), and nothing it answers says so, a SUBSCRIBE again "
    "included (granted whatever its ACL file says): the hold lasts as long as the main "
    "connection; ending it on a timer is what lastword.py rule 5 forbids"
)


def _reload_denying_reads(broker: Mosquitto, acl: Path, probe: Probe) -> None:
    """The ACL file rewritten and reloaded under the live connections; returns once mosquitto
    delivers no message on B/bridge/fence, told by the order of one client's messages (a
    probe's word on the fence topic is not back when its round trip after it is)."""
    acl.write_text(READ_DENIED)
    broker.reload()

    def unread() -> bool:
        mark = probe.mark()
        probe.publish(FENCE, b"read?")
        probe.caught_up()
        return not [m for m in probe.messages[mark:] if m.topic == FENCE and m.payload == b"read?"]

    wait_until(unread, 10, "mosquitto reloaded its ACL file")


@contextmanager
def _read_denied_bridge(tmp_path: Path) -> Iterator[tuple[Rig, Probe, object, App]]:
    with acl_rig(tmp_path, ALLOWED) as (rig, probe):
        emu, app = tower(rig, speed_deg_s=60.0)
        wait_until(lambda: app.mqtt._word.markers, 10, "the markers are read back")
        _reload_denying_reads(rig.broker, tmp_path / "acl", probe)
        yield rig, probe, emu, app


@pytest.mark.xfail(strict=True, reason=OPEN_REASON)
def test_r25_1_stop_then_target_back_to_back_reaches_the_target_after_the_acl_reload(
    tmp_path: Path,
) -> None:
    with _read_denied_bridge(tmp_path) as (_rig, probe, emu, app):
        with main_held_at(app, "rotor/stop", b"") as held:  # the stop lane reads it first
            probe.publish("rotor/stop", "", qos=0)  # a script: stop, ...
            probe.publish("rotor/target", "300", qos=0)  # ... then go to 300 instead
            wait_until(held.is_set, 10, "the main connection is at the STOP")
            wait_until(lambda: app.mqtt._word.holding, 10, "the stop lane carried out the STOP")
        wait_until(
            lambda: abs(emu.state().az_deg - 300) <= 3,  # type: ignore[attr-defined]
            30,
            "STOP then target 300, back to back: the rotor turned to 300 (it waits, unsaid, "
            "for a marker the broker never delivers)",
        )


@pytest.mark.parametrize("protocol", [paho.MQTTv5, paho.MQTTv311], ids=["5", "3.1.1"])
def test_mosquitto_grants_a_subscription_again_though_its_reloaded_acl_denies_reading_it(
    tmp_path: Path, protocol: paho.MQTTProtocolVersion
) -> None:
    """Why R25-1 stays open: the broker's answer to asking again. If a later mosquitto refuses
    it (0x87 under MQTT 5, 0x80 under 3.1.1), a re-SUBSCRIBE can tell the bridge its markers
    are unreadable (lastword.py rule 7's ``markers_denied``) without a clock."""
    acl = tmp_path / "acl"
    acl.write_text(ALLOWED)
    broker = Mosquitto(
        tmp_path / "broker", extra_conf=f"allow_anonymous true\nacl_file {acl}\nuser root"
    )
    broker.start()
    subacks: list[list[int]] = []
    acked = threading.Condition()

    def on_subscribe(_c: object, _u: object, _mid: int, codes: list, _p: object) -> None:
        with acked:
            subacks.append([code.value for code in codes])
            acked.notify_all()

    client = paho.Client(CallbackAPIVersion.VERSION2, client_id="r25-1", protocol=protocol)
    client.on_subscribe = on_subscribe
    probe = Probe(broker.port, "rotor/#")
    try:
        client.connect("127.0.0.1", broker.port)
        client.loop_start()

        def subscribe() -> list[int]:
            n = len(subacks)
            client.subscribe([(FENCE, 1), (HELLO, 1)])
            with acked:
                assert acked.wait_for(lambda: len(subacks) > n, slow(10)), "no SUBACK"
            return subacks[n]

        assert subscribe() == [1, 1]
        _reload_denying_reads(broker, acl, probe)
        assert subscribe() == [1, 1], "mosquitto now refuses a marker topic it denies reading"
    finally:
        client.loop_stop()
        client.disconnect()
        probe.close()
        broker.stop()
