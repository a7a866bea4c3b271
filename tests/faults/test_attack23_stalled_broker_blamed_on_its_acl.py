"""Attack 23, with real mosquitto frozen (SIGSTOP) for a while and the bridge on it: the
bridge's own keep-alive gives the stalled broker up (as docs/reliability.md says), and its next
try, connected to the frozen broker's socket and never answered, ends on the same keep-alive.
The log then says, at ERROR, "the MQTT broker closed the connection before accepting it (Keep
alive timeout): check the broker's log (its access rules for this client id and user, a
connection limit)", and of the stop lane "the MQTT broker closed the stop lane's connection:
Keep alive timeout (... check the broker's ACL and connection limits ...)": the broker closed
nothing (it was frozen; the bridge's client gave up on it), and a user who reads the journal
after a broker host's stall goes through ACLs and connection limits that were never at fault.
"""

from __future__ import annotations

import logging
import time

import pytest

from tests.faults.conftest import Rig
from tests.support import wait_until

KEEPALIVE_S = 5  # the least the settings take
FROZEN_S = 4.0 * KEEPALIVE_S  # the broker stalled: the fault's length (not a deadline)


def test_a_stalled_broker_is_not_said_as_one_that_refused_the_bridge(
    rig: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    rig.mqtt_extra = {"keepalive_s": KEEPALIVE_S}
    rig.add("tower", "rotorez", emu={"start_az_deg": 10})
    with caplog.at_level(logging.INFO, logger="bridge.interfaces.mqtt"):
        rig.start()
        rig.ready("tower")
        connected = caplog.text.count("connected to MQTT broker")
        rig.broker.pause()
        time.sleep(FROZEN_S)  # the broker frozen: the fault's length (not a deadline)
        rig.broker.resume()
        wait_until(
            lambda: caplog.text.count("connected to MQTT broker") > connected, 60, "reconnected"
        )
    blamed = [
        r.getMessage()
        for r in caplog.records
        if "Keep alive timeout" in r.getMessage()
        and ("ACL" in r.getMessage() or "access rules" in r.getMessage())
    ]
    assert not blamed, blamed
