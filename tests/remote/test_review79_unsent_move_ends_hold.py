"""Review 79 (interfaces/mqtt/remote.py rule 10): a later move of this remote ends a held
STOP's wait as it is handed to paho, before the broker took it. A move the broker never
acknowledges (the remote's own link stalls: rule 7 resets the connection, drops the move and
refuses it, "not sent again", rotctld ``RPRT -6``) still ends the wait of a STOP the broker took
into the station's dead connection: when the station's bridge connects again, nothing is sent
again, and the rotor turns on to the target the operator stopped, the operator told that the
STOP went (``RPRT 0``) and the move did not. Real parts: mosquitto, the remote's link
(RemoteLink) reaching it over a TCP route this test cuts and heals (attack 26's), the station's
bridge's words published as it would."""

from __future__ import annotations

import pytest

from bridge.core.errors import Refused
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


def test_a_move_the_broker_never_took_does_not_end_a_held_stops_wait(
    broker: Mosquitto, probe: Probe
) -> None:
    route = CuttableLink(broker.port)
    heard: list[tuple[str, bool]] = []
    link = halting_link(
        route.port,
        "remote-review79-unsent",
        lambda topic, payload, retain: heard.append((topic, retain)),
    )
    link.start()
    try:
        wait_until(lambda: link.subscribed_since is not None, slow(10), "the link subscribed")
        heard_turning(probe, heard)
        log_from = broker.log.stat().st_size
        link.send("rotor/stop", "stop", "DL1ABC", 5)  # taken; into the station's dead connection
        first = link.subscribed_since
        route.cut()  # the remote's own link stalls: the move never reaches the broker
        with pytest.raises(Refused):
            link.send(
                "rotor/target", '{"azimuth":100}', "DL1ABC", 5, lambda: None, after=("rotor/stop",)
            )
        route.heal()
        wait_until(lambda: link.subscribed_since not in (None, first), slow(30), "the link back")
        n = len(heard)
        probe.publish(STATE, b"online")  # the station's bridge connected again, clean session
        wait_until(lambda: (STATE, False) in heard[n:], slow(10), "its online heard live")
        still_turning_then_marker(broker, probe, link, heard, log_from)
    finally:
        link.stop()
        route.close()
    assert remote_published(broker, log_from) == [b"stop", b"stop", b"track"]
