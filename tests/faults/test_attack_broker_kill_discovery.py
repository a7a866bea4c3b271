"""Attack: the broker killed (SIGKILL, no persistence) again and again while the bridge publishes
its Home Assistant discovery on reconnecting, then started again on the same port: the bridge
comes back online, every discovery config is back, the rotor is online and nothing moved."""

from __future__ import annotations

import json
import random
import time
from functools import partial

from tests.faults.conftest import Rig, motion_frames
from tests.support import retained_snapshot, wait_until

PREFIX = "homeassistant"


def configs(port: int) -> dict[str, bytes]:
    snap = retained_snapshot(port, f"{PREFIX}/#")
    return {t: p for t, p in snap.items() if t.endswith("/config") and p}


def published_since(rig: Rig, t: float) -> bool:
    """The bridge published on the broker since ``t``: discovery, or its state."""
    state = rig.probe.last("rotor/bridge/state")
    found = any(m.topic.startswith(PREFIX) for m in rig.probe.messages if m.t >= t)
    return found or (state is not None and state.t >= t)


def test_broker_killed_mid_discovery_again_and_again_the_bridge_recovers_whole(rig: Rig) -> None:
    rig.add("tower", "rotorez", emu={"start_az_deg": 100, "jitter_deg": 0})
    rig.start()
    rig.ready("tower")
    want = configs(rig.broker.port)
    assert len(want) > 10
    rng = random.Random(7)
    for _ in range(5):
        rig.broker.kill()
        time.sleep(rng.uniform(1.5, 2.5))  # longer than a reconnect delay: no takeover look
        rig.broker.start()
        # the bridge reconnects (its own backoff) and publishes discovery: kill in the middle
        wait_until(partial(published_since, rig, time.monotonic()), 20, "the bridge reconnects")
        time.sleep(rng.uniform(0.0, 0.05))
    rig.broker.kill()
    rig.broker.start()
    t = time.monotonic()
    rig.probe.wait_value("rotor/bridge/state", "online", timeout_s=30, after=t)
    rig.probe.wait_value("rotor/availability", "online", timeout_s=10)
    wait_until(lambda: configs(rig.broker.port) == want, 15, "every discovery config back")
    snap = rig.retained()
    assert snap["rotor/bridge/state"] == b"online"
    assert snap["rotor/availability"] == b"online"
    assert json.loads(snap["rotor/status"])["available"] is True
    assert motion_frames(rig, "tower") == 0
    assert rig.app is not None and not rig.app.failed.is_set(), rig.app.failure
    rig.probe.publish("rotor/target", "160")
    rig.arrived("tower", 160, timeout_s=20)
