"""Attack 20: a nudge sent to the target topic. ``R/nudge`` takes ``+10`` and ``-10`` (turn by
that much: docs/mqtt.md), Home Assistant's nudge buttons send ``+10`` and ``-10``, and an
automation or a Node-RED flow pointed at ``R/target`` by mistake sends the same words there.
``R/target`` reads ``+10`` as the bearing 10 (payloads.py's number takes a sign) and turns a
rotor at 120 110 degrees the other way, to 10: the sender meant 130. The bridge refuses what
reads as meant for another topic (a bare two-letter preset's name, a target whose first field
is empty: ``,30`` meant as elevation 30 once turned the rotor to azimuth 30); a bearing with a
plus sign is such a payload. Real mosquitto, the Rotor-EZ emulator on a real pty; asserted:
the frames the controller received and R/error."""

from __future__ import annotations

import json
import time

from tests.integration.test_pointing_bridge import QUICK_BRIDGE, QUICK_EMU, motion_frames
from tests.support.rig import Rig


def test_a_signed_step_on_the_target_topic_is_refused_not_taken_as_a_bearing(rig: Rig) -> None:
    emu = rig.add("tower", emu={**QUICK_EMU, "start_az_deg": 120}, **QUICK_BRIDGE)
    rig.start()
    rig.ready("tower")
    t0 = time.monotonic()
    rig.probe.publish(rig.t("target"), "+10")
    # a barrier on the same connection: the bridge takes its messages in order, so "+10" was
    # judged before this refusal is said
    rig.probe.publish(rig.t("target"), "north")
    rig.probe.wait_for(rig.t("error"), lambda m: b"north" in m.payload, after=t0)
    errors = [json.loads(m.payload) for m in rig.probe.on(rig.t("error"))]
    assert [e for e in errors if e.get("command") == "target '+10'"], (
        f"'+10' on R/target was taken as a bearing: {errors}"
    )
    assert not motion_frames(emu, t0), "the rotor was sent to 10"
