"""Attack pass (atkn2): a flood of lease changes that change nothing erases the audit trail.

The audit trail folds floods of refusals and stops (runtime/audit.py rule 6) and of the same
target again (rule 9), so that one sender cannot roll the four files over and erase the line
of who turned the rotor. A release of a lease nobody holds, or the holder's claim renewed
again and again, changes nothing either: each is still a line of its own, never folded.
"""

from __future__ import annotations

import json

import paho.mqtt.client as paho
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


def test_a_flood_of_releases_of_a_free_lease_is_folded_like_any_flood(rig: Rig) -> None:
    rig.sections["audit_file"] = str(rig.tmp / "audit.jsonl")
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    app = rig.start()
    rig.ready("tower")
    c = _client(rig.broker.port)
    for _ in range(N):  # a release names whoever its payload says: nobody holds the lease
        c.publish("rotor/control/release", json.dumps({"operator": "X"}), qos=1).wait_for_publish(5)
    c.publish("rotor/target", "20", qos=1).wait_for_publish(5)  # marker: after the flood
    wait_until(lambda: any(e["command"] == "target '20'" for e in _lines(rig, app)), 10, "marker")
    releases = [e for e in _lines(rig, app) if "release" in str(e["command"])]
    c.loop_stop()
    c.disconnect()
    assert len(releases) <= FREE_LINES + 1, (
        f"{len(releases)} lines for {N} releases that changed nothing"
    )


def test_a_flood_of_the_holders_renewals_is_folded_like_any_flood(rig: Rig) -> None:
    rig.sections["audit_file"] = str(rig.tmp / "audit.jsonl")
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    app = rig.start()
    rig.ready("tower")
    c = _client(rig.broker.port)
    claim = json.dumps({"operator": "DL1ABC", "minutes": 30})
    for _ in range(N):
        c.publish("rotor/control/claim", claim, qos=1).wait_for_publish(5)
    c.publish("rotor/target", "20", qos=1).wait_for_publish(5)
    wait_until(lambda: any(e["command"] == "target '20'" for e in _lines(rig, app)), 10, "marker")
    claims = [e for e in _lines(rig, app) if "claim" in str(e["command"])]
    c.loop_stop()
    c.disconnect()
    assert len(claims) <= FREE_LINES + 1, f"{len(claims)} lines for {N} identical renewals"


def test_a_flood_of_lock_off_while_unlocked_is_folded_like_any_flood(rig: Rig) -> None:
    rig.sections["audit_file"] = str(rig.tmp / "audit.jsonl")
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    app = rig.start()
    rig.ready("tower")
    c = _client(rig.broker.port)
    for _ in range(N):
        c.publish("rotor/lock", "OFF", qos=1).wait_for_publish(5)
    c.publish("rotor/target", "20", qos=1).wait_for_publish(5)
    wait_until(lambda: any(e["command"] == "target '20'" for e in _lines(rig, app)), 10, "marker")
    offs = [e for e in _lines(rig, app) if "lock" in str(e["command"])]
    c.loop_stop()
    c.disconnect()
    assert len(offs) <= FREE_LINES + 1, f"{len(offs)} lines for {N} lock OFFs while unlocked"
