"""Review 67 (claim rule 5): what the older of two overlapping bridges says has no limit. Each
``online`` on a watched ``bridge/state`` after an ``offline`` logs the whole overlap at ERROR
(some 400 characters) and republishes ``B/bridge/info``; each ``offline`` logs a WARNING and
republishes it again. A client that may publish there (a flapping or hostile one: ``online``
and ``offline`` in turns, beside an info of a younger bridge, so that the running bridge never
yields) writes two log lines per pair with nothing in between: past journald's default limit
(10,000 in 30 s), which then drops every line of the service, its safety warnings too (the harm
test_attack_log_flood.py and owned.py's 2 s per topic were written against)."""

from __future__ import annotations

import json
import logging

import pytest

from bridge.interfaces.mqtt.claim import Instance
from tests.support import Probe, retained_snapshot, wait_until
from tests.support.rig import Rig

BURST = 200  # pairs of online and offline


def test_a_flapping_overlapping_bridge_is_not_logged_line_by_line(
    rig: Rig, probe: Probe, caplog: pytest.LogCaptureFixture
) -> None:
    rig.add("tower")
    rig.add("yagi")
    app = rig.start()
    rig.ready("tower")
    younger = Instance("rotor-flap-0001", "elsewhere", 9, app.me.started_unix + 60)
    probe.publish("rotor/tower/bridge/info", younger.info([]), retain=True)
    with caplog.at_level(logging.INFO, logger="bridge.interfaces.mqtt.look"):
        for _ in range(BURST):
            probe.publish("rotor/tower/bridge/state", "online")
            probe.publish("rotor/tower/bridge/state", "offline")
        probe.publish("rotor/tower/bridge/state", "online", retain=True)  # the last word

        def said() -> bool:
            info = retained_snapshot(rig.broker.port, "rotor/bridge/info")["rotor/bridge/info"]
            return any("rotor-flap-0001" in p for p in json.loads(info)["problems"])

        wait_until(said, 20, "the last online said on B/bridge/info")
    assert not app.failed.is_set()
    lines = [
        r
        for r in caplog.records
        if "rotor/tower" in r.getMessage() and r.name == "bridge.interfaces.mqtt.look"
    ]
    assert len(lines) <= 10, f"{len(lines)} log lines for {BURST} flaps"
