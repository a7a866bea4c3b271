"""Cold review 23: ordinary use, an idle bridge, nothing lost. A Home Assistant script or a
Node-RED flow publishes two words back to back from one client: STOP then a new target ("stop,
then go there instead"), or lock ON then lock OFF. Each is published after the other, the
broker has them in that order, and nothing is behind on either connection. Since 0785d896 the
stop lane's hold ends by its marker alone, and the marker is published by the bridge only after
the lane read the STOP: the second word, already at the broker, reaches the main connection
before the marker and is refused as "published before a STOP or lock ON ... (or not known to be
after it)". The user's last word is not carried out, and R/error blames an order the user never
published.
"""

from __future__ import annotations

import time

from tests.integration.test_last_word import tower
from tests.support.rig import Rig


def test_stop_then_a_target_back_to_back_turns_to_the_target(rig: Rig) -> None:
    emu, app = tower(rig)
    rig.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving, 10)
    t = time.monotonic()
    rig.probe.publish("rotor/stop", "", qos=0)  # the script (QoS 0: Home Assistant's default): stop ...
    rig.probe.publish("rotor/target", "100", qos=0)  # ... then go to 100 instead
    time.sleep(1.0)
    errors = [m.payload for m in rig.probe.on("rotor/error") if m.t >= t]
    assert not [e for e in errors if b"target '100'" in e], (
        f"the target published after the STOP was refused as older: {errors}"
    )
    emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 100) <= 3, 30)

