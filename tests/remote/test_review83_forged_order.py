"""Review 83 (interfaces/mqtt/remote.py rule 10): a held halt is stamped with the ``taken`` of
the last ``R/status`` the remote read, whoever published it. ``R/status`` is a topic every
client that may write the station's topics can publish on (a second bridge given the same
base topic, a script, a replay tool), and the remote believes any ``order`` it reads there:

- a status whose ``taken`` is far ahead of the station's (same run) stamps the next STOP so
  high that no turn the station really takes after it is ever "after the stamp": the STOP
  lost in a partition is sent again when the station's bridge connects again and stops Home
  Assistant's NEWER turn (an old halt overriding a newer command), and stays held for every
  later reconnect until a status shows no turn;
- a status naming another run stamps the STOP with that run: the station's next genuine
  status (its real run) ends the hold at once, and a STOP lost in the partition is never
  sent again (the rotor turns on to its old target).

The station's own statuses in one run never go back in ``taken``; the remote could tell a
status that does from the station's (or at least not let one status move the stamp past
what the station's next one confirms), but it takes the last one read as truth.
Real parts: mosquitto, the remote's link (RemoteLink), the station's and the forger's words
published as they would be."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from bridge.interfaces.mqtt.heartbeat import beat_payload
from bridge.interfaces.mqtt.remote import RemoteLink
from bridge.settings.mqtt import MqttSettings
from tests.remote.test_attack26_stop_into_a_partition import (
    STATUS,
    rotor_standing,
    turning_status,
)
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.remote import remote_published
from tests.support.waiting import slow

STATE, BEAT = "rotor/bridge/state", "rotor/bridge/heartbeat"


def _link(broker: Mosquitto, heard: list[str]) -> RemoteLink:
    return RemoteLink(
        MqttSettings(host="127.0.0.1", port=broker.port),
        "remote-review83-forged",
        [BEAT, STATE, STATUS],
        lambda topic, payload, retain: heard.append(topic),
        last_word=lambda topic, payload: topic == "rotor/stop",
        heartbeat=BEAT,
        station_state=STATE,
        proof=rotor_standing,
    )


def _words(probe: Probe, heard: list[str]) -> Callable[[str, bytes], None]:
    def say(topic: str, payload: bytes) -> None:  # published, and read by the remote
        n = len(heard)
        probe.publish(topic, payload, qos=0)
        wait_until(lambda: len(heard) > n, slow(10), f"{topic} heard")

    return say


@contextmanager
def _station_turning(
    broker: Mosquitto, probe: Probe
) -> Iterator[tuple[RemoteLink, Callable[[str, bytes], None]]]:
    """The remote's link subscribed, and the station heard turning to a target it took at
    place 1; the link stopped at the end."""
    heard: list[str] = []
    link = _link(broker, heard)
    link.start()
    try:
        wait_until(lambda: link.subscribed_since is not None, slow(10), "the link subscribed")
        say = _words(probe, heard)
        say(BEAT, beat_payload(time.time()).encode())
        say(STATUS, turning_status(1))  # the station: turning to a target taken at place 1
        yield link, say
    finally:
        link.stop()


def _marker(link: RemoteLink, broker: Mosquitto, log_from: int) -> None:
    """A marker behind anything the link sends again, and the wait for it at the broker."""
    link.send("rotor/track", "off", "DL1ABC", 5)
    wait_until(lambda: len(remote_published(broker, log_from)) >= 2, slow(10), "the marker")


def test_a_forged_status_far_ahead_never_lets_an_old_stop_stop_a_newer_turn(
    broker: Mosquitto, probe: Probe
) -> None:
    with _station_turning(broker, probe) as (link, say):
        say(STATUS, turning_status(1, taken=10**15))  # a client with write access on R/status
        log_from = broker.log.stat().st_size
        link.send("rotor/stop", "stop", "DL1ABC", 5)  # into the station's dead connection
        # the station's bridge connects again (a clean session: the STOP lost) and takes Home
        # Assistant's target, asked after the STOP: place 2 of its run
        say(STATE, b"online")
        say(STATUS, turning_status(2))
        say(BEAT, beat_payload(time.time()).encode())
        _marker(link, broker, log_from)
    assert remote_published(broker, log_from) == [b"stop", b"track"], (
        "the old STOP went again and stopped the station's newer turn (place 2)"
    )


def test_a_forged_status_of_another_run_never_loses_a_held_stop(
    broker: Mosquitto, probe: Probe
) -> None:
    with _station_turning(broker, probe) as (link, say):
        say(STATUS, turning_status(1, run="forged"))  # a client with write access on R/status
        log_from = broker.log.stat().st_size
        link.send("rotor/stop", "stop", "DL1ABC", 5)  # into the station's dead connection
        say(STATUS, turning_status(1))  # the station's own, still turning: it never had it
        say(STATE, b"online")  # its bridge connected again, a clean session
        say(STATUS, turning_status(1))  # still turning to the target the STOP was asked against
        say(BEAT, beat_payload(time.time()).encode())
        _marker(link, broker, log_from)
    assert remote_published(broker, log_from) == [b"stop", b"stop", b"track"], (
        "the STOP the station never took was not sent again after it connected again"
    )
