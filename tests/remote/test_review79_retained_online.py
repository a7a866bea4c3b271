"""Review 79 (interfaces/mqtt/remote.py rule 10): a STOP the broker took but the station never
showed it has is sent again only when the station's bridge says ``online`` as published. When
the remote's own connection drops too and comes back after the station's bridge connected
again (a broker restart: both sides connect again, the station's bridge first; or the remote's
own link down meanwhile), the station's ``online`` reaches the remote only as the broker's
retained replay, and nothing sends the held STOP again: it stays held, its one chance missed.
Real parts: mosquitto, the remote's link (RemoteLink) reaching it over a TCP route this test
cuts and heals (attack 26's), the station's bridge's words published as it would."""

from __future__ import annotations

from tests.remote.test_attack26_stop_into_a_partition import (
    CuttableLink,
    halting_link,
    heard_turning,
    still_turning_then_marker,
)
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.remote import remote_published
from tests.support.waiting import slow

STATE = "rotor/bridge/state"


def test_a_held_stop_goes_again_when_the_station_came_back_while_the_remote_was_away(
    broker: Mosquitto, probe: Probe
) -> None:
    route = CuttableLink(broker.port)
    heard: list[tuple[str, bool]] = []
    link = halting_link(
        route.port, "remote-review79", lambda topic, payload, retain: heard.append((topic, retain))
    )
    link.start()
    try:
        wait_until(lambda: link.subscribed_since is not None, slow(10), "the link subscribed")
        probe.publish(STATE, b"online", retain=True)
        n = heard_turning(probe, heard)
        log_from = broker.log.stat().st_size
        link.send("rotor/stop", "stop", "DL1ABC", 5)  # taken; into the station's dead connection
        first = link.subscribed_since
        route.cut()  # the remote's connection dies too (the broker restarting) ...
        probe.publish(STATE, b"offline", retain=True)  # ... the station's bridge's will, and
        probe.publish(STATE, b"online", retain=True)  # its bridge back, a clean session
        route.heal()  # the remote connects again: the station's online is a retained replay
        wait_until(lambda: link.subscribed_since not in (None, first), slow(30), "the link back")
        wait_until(lambda: (STATE, True) in heard[n:], slow(10), "the replayed online")
        still_turning_then_marker(broker, probe, link, heard, log_from)
    finally:
        link.stop()
        route.close()
    assert remote_published(broker, log_from) == [b"stop", b"stop", b"track"]
