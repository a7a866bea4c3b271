"""Review 108: a lock ON the stop express reads early (before its sync word is back:
express.py rule 11, a6477fe9) is set by the bridge unless one of its connections read a lock ON
of that rotator since; nothing orders it against a lock OFF. A lock ON the express alone had
(a second press of the lock while the bridge's connections were coming back after a broker
restart), read by it late, locks the rotator again after the operator's lock OFF published
after it: the operator unlocked and saw R/lock/state OFF, and then the lock is ON again (kept
across restarts) and every target refused.

Real mosquitto, the bridge in this process, the express in its own, a Rotor-EZ on a real pty;
the express reads late behind the gate of
tests/integration/test_stop_before_the_express_words_are_back.py, its sync words dropped by an
ACL (so every lock ON it reads is early).
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.integration.express_gate import (
    OPEN,
    Gate,
    acl_conf,
    gated_start,
    words_dropped,
)
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import wait_until


@pytest.fixture
def broker_conf(tmp_path: Path) -> str:
    return acl_conf(tmp_path, OPEN)


@pytest.mark.xfail(
    strict=True,
    reason="review 108: a lock ON the stop express reads late and early locks the rotator "
    "after a lock OFF published after it; targets are refused as locked",
)
def test_an_early_lock_on_read_late_does_not_undo_a_lock_off_published_after_it(
    tmp_path: Path, broker: Mosquitto, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.DEBUG, logger="bridge.interfaces.mqtt.express")
    gate = Gate(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, gate, probe) as rig:
            emu, settings, app = gated_start(
                rig, gate, emu={"start_az_deg": 10, "speed_deg_s": 20.0}
            )
            assert probe.publish("rotor/lock", "ON")  # locked for work on the tower
            probe.wait_value("rotor/lock/state", "ON")
            bridge_ids = {
                settings.effective_client_id(),
                lane_client_id(settings),
                lane_client_id(settings, "lock"),
            }
            gate.refused |= bridge_ids  # the bridge's connections back after the lock ON
            words_dropped(app, broker, tmp_path)
            gate.hold(True)  # the express reads what the broker sends it late
            assert probe.publish("rotor/lock", "ON")  # 1: locked again (a second press)
            gate.refused -= bridge_ids
            wait_until(
                lambda: all(
                    c.subscribed_since is not None for c in (app.client, app.lane, app.lock_lane)
                ),
                15,
                "the bridge's connections back and subscribed",
            )
            off = time.monotonic()
            assert probe.publish("rotor/lock", "OFF")  # 2: the work done, unlocked
            probe.wait_value("rotor/lock/state", "OFF", after=off)  # (the bridge read it)
            gate.hold(False)  # the express reads the older lock ON now (early)
            wait_until(
                lambda: any("lock ON read" in r.getMessage() for r in caplog.records),
                10,
                "the express's lock ON said to the bridge",
            )
            mark = probe.mark()
            assert probe.publish("rotor/target", "100")  # 3: a turn after the unlock

            def refused() -> list[str]:
                return [m.text for m in probe.messages[mark:] if m.topic == "rotor/error"]

            def moving() -> bool:
                return emu.wait_for(lambda s: True).is_moving

            wait_until(lambda: refused() or moving(), 10, "the target refused or carried out")
            assert not refused(), f"the target after the lock OFF refused: {refused()}"
            rig.arrived("tower", 100)
    finally:
        probe.close()
        gate.close()
