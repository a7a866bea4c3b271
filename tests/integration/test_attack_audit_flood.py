"""Attack pass (atkn2): a flood of lease changes that change nothing erases the audit trail.

The audit trail folds floods of refusals and stops (runtime/audit.py rule 6) and of the same
target again (rule 9), so that one sender cannot roll the four files over and erase the line
of who turned the rotor. A release of a lease nobody holds, or the holder's claim renewed
again and again, changes nothing either: each is still a line of its own, never folded.
"""

from __future__ import annotations

import json

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge.runtime.audit import FREE_LINES
from tests.support import wait_until
from tests.support.rig import Rig

N = 400


def _client(port: int) -> paho.Client:
    c = paho.Client(CallbackAPIVersion.VERSION2, client_id="audit-flood", protocol=paho.MQTTv5)
    c.connect("127.0.0.1", port)
    c.loop_start()
    return c


def _lines(rig: Rig, app: object) -> list[dict[str, object]]:
    app.audit.flush()  # type: ignore[attr-defined]
    path = rig.tmp / "audit.jsonl"
    return [json.loads(x) for x in path.read_text().splitlines()]


@pytest.mark.parametrize(
    ("topic", "payload", "word", "what"),
    [
        # a release names whoever its payload says: nobody holds the lease
        (
            "rotor/control/release",
            json.dumps({"operator": "X"}),
            "release",
            "releases that changed nothing",
        ),
        (
            "rotor/control/claim",
            json.dumps({"operator": "DL1ABC", "minutes": 30}),
            "claim",
            "identical renewals",
        ),
        ("rotor/lock", "OFF", "lock", "lock OFFs while unlocked"),
    ],
    ids=["release-free", "renew", "lock-off-unlocked"],
)
def test_a_flood_of_commands_that_change_nothing_is_folded_like_any_flood(
    rig: Rig, topic: str, payload: str, word: str, what: str
) -> None:
    rig.sections["audit_file"] = str(rig.tmp / "audit.jsonl")
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    app = rig.start()
    rig.ready("tower")
    c = _client(rig.broker.port)
    for _ in range(N):
        c.publish(topic, payload, qos=1).wait_for_publish(5)
    c.publish("rotor/target", "20", qos=1).wait_for_publish(5)  # marker: after the flood
    wait_until(lambda: any(e["command"] == "target '20'" for e in _lines(rig, app)), 10, "marker")
    lines = [e for e in _lines(rig, app) if word in str(e["command"])]
    c.loop_stop()
    c.disconnect()
    assert len(lines) <= FREE_LINES + 1, f"{len(lines)} lines for {N} {what}"
