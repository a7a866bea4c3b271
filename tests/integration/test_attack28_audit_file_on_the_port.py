"""Attack 28: ``audit_file`` naming the rotator's own serial port (the adapter's
``/dev/serial/by-id/`` name pasted into the wrong line) passes ``check-config`` ("config OK";
a ``state_file`` there is refused: "it is a character device, not a regular file"). The audit
writer opens it as a file (O_APPEND|O_NONBLOCK|O_NOCTTY goes through on a tty) and every audit
line goes down the controller's line: the Rotor-EZ reads the JSON's letters as its one-letter
commands (endpoint, overshoot and unstick switched off: ``e``, ``o``, ``s``), the bridge's own
frames get garbled ("answers only garbled replies ... while the rotor turned"), and a payload
the bridge *refused* reaches the controller inside its audit line: ``AP1200;AM1;`` published on
``R/target`` is refused on R/error ("target must be 'azimuth' ..."), and the controller stores
200 and executes ``AM1;``, a turn nobody was allowed to ask for.

Real mosquitto, the Rotor-EZ emulator on a real pty (its by-id-style link as the port). A fix
refuses the configuration naming audit_file (the test then ends there), or keeps the audit out
of the line."""

from __future__ import annotations

import contextlib
import json

import pytest
from pydantic import ValidationError

from tests.support.rig import Rig
from tests.support.waiting import slow

REFUSED = "AP1200;AM1;"  # a Rotor-EZ's target and move, as a payload R/target refuses
AUDIT_WRITE_S = 5.0  # the audit writer's line after its R/audit message, on a loaded machine


def test_an_audit_file_on_the_rotators_port_sends_nothing_to_the_controller(rig: Rig) -> None:
    emu = rig.add("tower", "rotorez")
    rig.sections = {"audit_file": rig.rotators[0]["port"]}
    try:
        rig.settings  # noqa: B018 (validated: a refusal naming the key is the fix)
    except ValidationError as exc:
        assert "audit_file" in str(exc), exc
        return
    rig.start()
    rig.ready("tower")
    mark = rig.probe.mark()
    rig.probe.publish(rig.t("target"), REFUSED)
    audit = rig.probe.wait(
        lambda m: m.topic == rig.t("audit") and REFUSED in json.loads(m.payload)["command"],
        AUDIT_WRITE_S,  # (scaled by the probe)
        "the refused target's audit line",
        mark,
    )
    assert json.loads(audit.payload)["result"] != "executed", audit.payload
    with contextlib.suppress(TimeoutError):
        frame = emu.wait_for_frame(b"AP1200;", timeout_s=slow(AUDIT_WRITE_S))
        pytest.fail(f"the controller got the refused target through the audit file: {frame}")
