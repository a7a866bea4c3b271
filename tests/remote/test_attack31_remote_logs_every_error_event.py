"""Attack 31 (resources under churn): the remote writes a WARNING for every error event it reads.

run.py rule 7 logs what the station refuses, as it comes on a rotator's ``R/error``, one line
per message and no limit. The station itself sends at most a burst and then a few a second on
that topic (interfaces/mqtt/service.py, its EventLimiter), but the remote logs whatever the
broker hands it: anyone who may publish there (a neighbour on a shared broker, a flow gone
wrong) writes the operator's log for him, a line per message, for as long as he likes. The
station's own logs, the TCP ports' (tcplines.py rule 5) and the console's are held to a burst
and a pace, with a count of what was left out.

Real parts: mosquitto, the bridge on an emulated Rotor-EZ (tests/remote/conftest.py), the
remote in this process with a rotctld endpoint, and a neighbour's MQTT client.
"""

from __future__ import annotations

import json
import logging

import pytest

from tests.support.mosquitto import free_port
from tests.support.mqtt import Probe
from tests.support.remote import running_remote
from tests.support.rig import Rig
from tests.support.waiting import wait_until

FLOOD = 500
SAID = "the station says:"


def _event(message: str) -> str:
    return json.dumps({"kind": "refused", "message": message, "command": "100", "time": 1.0})


def test_a_flood_of_error_events_is_a_few_lines_in_the_remotes_log(
    station: Rig, probe: Probe, caplog: pytest.LogCaptureFixture
) -> None:
    endpoint = {"rotator": "tower", "rotctld_port": free_port()}
    with running_remote(station.broker.port, "DL1ABC", endpoint) as remote:
        caplog.set_level(logging.WARNING, logger="bridge.remote.run")
        caplog.clear()
        for i in range(FLOOD):  # (not retained, as the station's own: rule 7 logs them)
            probe.publish("rotor/error", _event(f"flood {i}"))
        last = _event("the last").encode()
        probe.publish("rotor/error", last)
        wait_until(lambda: remote.view.get("rotor/error") == last, 30, "the flood read")
        said = [r for r in caplog.records if SAID in r.getMessage()]

    # a burst and a few a second, as every other log of the bridge's is held to (the flood
    # takes a second or two here): a fifth of the flood is far more than that
    assert len(said) <= FLOOD // 5, f"{len(said)} lines for {FLOOD + 1} error events"
