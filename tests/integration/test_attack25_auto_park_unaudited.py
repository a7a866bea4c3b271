"""Attack 25: an auto-park turns the rotor and the audit trail says nothing of it.

The auto-park feature's declaration (bridge/features/autopark/__init__.py) says what users see of
it: "a park like any, its source ``auto-park`` in ``R/status`` and the audit". The audit trail is
the station's record of who did what (docs/mqtt.md, "the audit trail"). Here a Rotor-EZ on a pty
(real pyserial, a private mosquitto) is sent to 110 by an operator, then auto-parks to 0 after
its quiet spell: the controller gets ``AP1000`` and the rotor turns 110 degrees, ``R/status``
says ``auto-park``, and the audit file's last word on that rotator is still the operator's
``target '110'``: nothing says the bridge turned it back.
"""

from __future__ import annotations

import json
import time

from tests.integration.test_pointing_bridge import PARK_FRAME, PARKING, PARKING_EMU, start
from tests.support import wait_until
from tests.support.rig import Rig
from tests.support.waiting import slow


def _lines(rig: Rig) -> list[dict[str, object]]:
    assert rig.app is not None
    rig.app.audit.flush()
    path = rig.tmp / "audit.jsonl"
    return [json.loads(x) for x in path.read_text().splitlines()] if path.exists() else []


def test_an_auto_park_that_turns_the_rotor_is_in_the_audit_trail(rig: Rig) -> None:
    rig.sections["audit_file"] = str(rig.tmp / "audit.jsonl")
    emu = rig.add("tower", emu={**PARKING_EMU, "start_az_deg": 100}, **PARKING)
    start(rig)
    t_cmd = time.monotonic()
    rig.probe.publish("rotor/target", "110")
    park = emu.wait_for_frame(PARK_FRAME, timeout_s=15)
    assert park.outcome == "executed"
    rig.probe.wait_for(
        "rotor/status",
        lambda m: json.loads(m.payload)["last_command_source"] == "auto-park",
        after=t_cmd,
    )
    emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg) <= 0.5, 10)  # the rotor parked
    wait_until(
        lambda: any(e["command"] == "target '110'" for e in _lines(rig)),
        slow(5),
        "the operator's target in the audit file",
    )
    lines = _lines(rig)
    after = lines[[e["command"] for e in lines].index("target '110'") + 1 :]
    assert any("auto-park" in json.dumps(e) for e in after), (
        f"the rotor was turned from 110 to the park by auto-park; the audit file after the "
        f"operator's target: {after}"
    )
