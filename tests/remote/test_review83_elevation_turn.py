"""Review 83 (remote/readings.py ``status_order``, interfaces/mqtt/remote.py rule 10): the turn a
held STOP ends is read from ``R/status``'s ``target`` (the AZIMUTH target), ``tracking`` and
``following``; ``target_elevation`` is not looked at. A status showing the elevation still
turning to its target with no azimuth target reads as "no turn", and the STOP is taken for
done. That status is what a composite az/el rotator publishes once its azimuth box arrived
and its elevation box turns on (runtime/composite.py ``merge``: ``target`` is the azimuth
box's, ``target_elevation`` the elevation box's), and what an az/el box shows for an
elevation-only target (Home Assistant's elevation entity commands ``R/target_elevation``).
A STOP the broker took into the station's dying connection is then dropped at the station's
first status after it connected again, never sent again, and the elevation turns on to the
target the operator stopped.
Real parts: mosquitto, the remote's link (RemoteLink), the station's words published as its
bridge publishes them."""

from __future__ import annotations

import json
import time

import pytest

from bridge.interfaces.mqtt.heartbeat import beat_payload
from bridge.interfaces.mqtt.remote import RemoteLink
from bridge.settings.mqtt import MqttSettings
from tests.remote.test_attack26_stop_into_a_partition import STATUS, rotor_standing
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.remote import remote_published
from tests.support.waiting import slow

STATE, BEAT = "rotor/bridge/state", "rotor/bridge/heartbeat"


def elevation_turning(turn: int, state: str = "moving") -> bytes:
    """``R/status`` (the fields rule 10 reads) of an az/el rotator whose elevation turns to a
    target taken at place ``turn``, its azimuth at rest with none; ``state`` ``idle``: the
    target taken, its turn not begun yet (the box's start delay, the brake's)."""
    order = {"run": "run-1", "taken": turn, "turn": turn, "lock": 0}
    doc = {
        "target": None,
        "target_elevation": 60.0,
        "state": state,
        "moving": state == "moving",
        "locked": False,
        "order": order,
    }
    return json.dumps(doc).encode()


@pytest.mark.parametrize("state", ["moving", "idle"])
def test_a_stop_held_over_an_elevation_turn_goes_again(
    broker: Mosquitto, probe: Probe, state: str
) -> None:
    heard: list[str] = []
    link = RemoteLink(
        MqttSettings(host="127.0.0.1", port=broker.port),
        "remote-review83-elevation",
        [BEAT, STATE, STATUS],
        lambda topic, payload, retain: heard.append(topic),
        last_word=lambda topic, payload: topic == "rotor/stop",
        heartbeat=BEAT,
        station_state=STATE,
        proof=rotor_standing,
    )
    link.start()
    try:
        wait_until(lambda: link.subscribed_since is not None, slow(10), "the link subscribed")

        def say(topic: str, payload: bytes) -> None:  # the station's bridge's word
            n = len(heard)
            probe.publish(topic, payload, qos=0)
            wait_until(lambda: len(heard) > n, slow(10), f"{topic} heard")

        say(BEAT, beat_payload(time.time()).encode())
        say(STATUS, elevation_turning(1, state))  # the elevation's target taken at place 1
        log_from = broker.log.stat().st_size
        link.send("rotor/stop", "stop", "DL1ABC", 5)  # into the station's dead connection
        say(STATE, b"online")  # its bridge connected again, a clean session: the STOP lost
        say(STATUS, elevation_turning(1, state))  # still the target the STOP was against
        say(BEAT, beat_payload(time.time()).encode())
        link.send("rotor/track", "off", "DL1ABC", 5)  # a marker behind anything sent again
        wait_until(lambda: len(remote_published(broker, log_from)) >= 2, slow(10), "the marker")
    finally:
        link.stop()
    assert remote_published(broker, log_from) == [b"stop", b"stop", b"track"], (
        "the STOP the station never took was not sent again over the elevation's turn"
    )
