"""Attack 20: a number as a string, in the control lease's claim. docs/mqtt.md says of every
payload: numbers are written in ASCII, "in JSON a number, or a string that holds one", and
``R/target`` takes ``{"azimuth": "123"}``. A claim's ``{"minutes": "30"}`` (what a Node-RED
change node or a dashboard's text box makes) is refused "minutes must be a number", and the
operator is not given the lease the documentation says such a claim takes. Real mosquitto,
the Rotor-EZ emulator on a real pty; asserted: the retained R/control and R/error."""

from __future__ import annotations

import json
import time

from tests.support.rig import Rig


def test_a_claim_whose_minutes_are_a_string_holding_a_number_takes_the_lease(rig: Rig) -> None:
    rig.add("tower")
    rig.start()
    rig.ready("tower")
    t0 = time.monotonic()
    rig.probe.publish(rig.t("control/claim"), json.dumps({"operator": "DL1ABC", "minutes": "30"}))
    # a barrier on the same connection: the claim was judged before this refusal is said
    rig.probe.publish(rig.t("target"), "north")
    rig.probe.wait_for(rig.t("error"), lambda m: b"north" in m.payload, after=t0)
    refused = [
        json.loads(m.payload)["message"]
        for m in rig.probe.on(rig.t("error"))
        if json.loads(m.payload).get("command", "").startswith("claim")
    ]
    assert not refused, refused
    held = rig.probe.wait_for(rig.t("control"), lambda m: b"DL1ABC" in m.payload, after=t0)
    assert json.loads(held.payload)["holder"] == "DL1ABC"
