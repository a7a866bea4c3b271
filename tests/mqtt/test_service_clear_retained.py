"""Deleting a retained command (an empty retained message, as the bridge's own refusals advise)
is no command: no error event, nothing moves. An empty plain message is still a bad payload.

Real parts: mosquitto, the bridge (App) and an emulated Rotor-EZ on a pty (tests/support's
rig), MQTT 5 (the retain flag of live messages reaches the bridge).
"""

from __future__ import annotations

import json
import time

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from tests.support.rig import Rig


def test_an_empty_retained_command_is_a_deletion_not_a_refused_command(rig: Rig) -> None:
    emu = rig.add("tower", emu={"start_az_deg": 10})
    rig.start()
    rig.ready("tower")
    stops = len(emu.frames("stop"))
    t = time.monotonic()
    for leaf in ("target", "stop", "target/elevation", "lock", "option/jam"):
        rig.probe.publish(f"rotor/{leaf}", "", retain=True)
    # an empty plain target after them: still refused, and its error marks that the bridge has
    # handled everything before it (one publisher, one subscriber: in order)
    rig.probe.publish("rotor/target", "")
    err = rig.probe.wait_for("rotor/error", after=t)
    assert json.loads(err.payload)["message"] == "empty payload"
    assert json.loads(err.payload)["command"] == "target"
    # a sync round trip: a refused command sent last is the next and last error
    rig.probe.publish("rotor/target", "sync")
    rig.probe.wait_for("rotor/error", lambda m: b"sync" in m.payload, after=t)
    errors = [json.loads(m.payload) for m in rig.probe.on("rotor/error") if m.t >= t]
    assert [e["message"] for e in errors] == [
        "empty payload",
        "azimuth must be a number, got 'sync'",
    ], errors
    assert emu.frames(*BEARING_OUTCOMES) == []
    assert len(emu.frames("stop")) == stops  # the deleted stop did not stop anything either
    assert not emu.state().is_moving
    assert rig.retained()["rotor/lock/state"] == b"OFF"


def test_an_empty_plain_stop_still_stops(rig: Rig) -> None:
    """A stop takes any payload (README: never refused); only the retained empty one is a
    deletion."""
    emu = rig.add("tower", emu={"start_az_deg": 0, "speed_deg_s": 20})
    rig.start()
    rig.ready("tower")
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 20)
    rig.probe.publish("rotor/stop", "")
    stopped = emu.wait_for(lambda s: not s.is_moving, 5)
    assert stopped.az_deg < 250
