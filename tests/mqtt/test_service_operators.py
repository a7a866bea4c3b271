"""Who sent an MQTT command (the user property ``operator``), the control lease's topics and
``R/audit``, at the service: a recording rotator and publisher, no broker."""

from __future__ import annotations

import json

from bridge.core.model import AuditEvent, Control, Origin, RotatorStatus, Source, Stop
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.mqtt.test_service import RecordingRotator, service


def test_the_user_property_names_the_operator_and_a_bad_one_is_ignored() -> None:
    svc, _, rots = service({"tower": "rotorez"})
    svc.on_message("rotor/target", b"120", False, "DL1ABC")
    svc.on_message("rotor/park", b"PARK", False, " G4XYZ ")
    svc.on_message("rotor/target", b"130", False, "\x1b[2J evil")  # not printable: ignored
    svc.on_message("rotor/target", b"140", False, "x" * 33)  # too long: ignored
    svc.on_message("rotor/target", b"150", False)  # none (MQTT 3.1.1, or not set)
    svc.on_lane_message("rotor/stop", b"STOP", False, "DL1ABC")  # the stop lane too
    assert rots["tower"].origins == [
        Origin(Source.MQTT, "DL1ABC"),
        Origin(Source.MQTT, "G4XYZ"),
        Origin(Source.MQTT),
        Origin(Source.MQTT),
        Origin(Source.MQTT),
        Origin(Source.MQTT, "DL1ABC"),
    ]
    assert rots["tower"].calls[-1] == ("submit", Stop(), "stop 'STOP'", 1)


def test_claims_and_releases_reach_the_lease_and_bad_or_retained_ones_change_nothing() -> None:
    svc, _, rots = service({"tower": "rotorez"})
    rot = rots["tower"]
    svc.on_message("rotor/control/claim", b'{"operator": "DL1ABC", "minutes": 30}', False)
    svc.on_message("rotor/control/claim", b'{"minutes": 5}', False, "G4XYZ")  # its own name
    svc.on_message("rotor/control/claim", b"{not json", False, "G4XYZ")
    svc.on_message("rotor/control/claim", b'{"operator": "G4XYZ"}', False)
    svc.on_message("rotor/control/claim", b'{"minutes": 5}', False)  # nobody named
    svc.on_message("rotor/control/claim", b'{"operator": "X", "minutes": 5, "a": 1}', False)
    svc.on_message("rotor/control/claim", b'{"operator": "G4XYZ", "minutes": 5}', True)
    svc.on_message("rotor/control/release", b"", False, "DL1ABC")
    svc.on_message("rotor/control/release", b'{"operator": "homeassistant"}', False)
    claims = [c for c in rot.calls if c[0] in ("claim", "release_control")]
    assert claims == [
        ("claim", "DL1ABC", 30, 'claim \'{"operator": "DL1ABC", "minutes": 30}\''),
        ("claim", "G4XYZ", 5, "claim '{\"minutes\": 5}'"),
        ("release_control", "release"),
        ("release_control", 'release \'{"operator": "homeassistant"}\''),
    ]
    assert rot.origins[-2:] == [Origin(Source.MQTT, "DL1ABC"), Origin(Source.MQTT, "homeassistant")]
    refusals = [c[1] for c in rot.calls if c[0] == "refused"]
    assert refusals[0].startswith("bad JSON")
    assert 'a claim needs "minutes"' in refusals[1]
    assert 'a claim needs "operator"' in refusals[2]
    assert "unknown key(s) in a claim: a" in refusals[3]
    assert "retained command on rotor/control/claim ignored" in refusals[4]  # rule 7 of the house
    assert len(refusals) == 5


def test_the_lease_is_published_retained_from_the_status_and_audit_events_as_they_come() -> None:
    svc, pub, _ = service({"tower": "rotorez"})
    held = Control("DL1ABC", 1_700_001_800.0)
    svc.publish_status("tower", RotatorStatus("tower", control=held, last_operator="DL1ABC"))
    assert pub.retained["rotor/control"] == (
        '{"holder":"DL1ABC","until":"2023-11-14T22:43:20.000+00:00"}'
    )
    status = json.loads(pub.retained["rotor/status"])
    assert status["control"] == {"holder": "DL1ABC", "until": "2023-11-14T22:43:20.000+00:00"}
    assert status["last_operator"] == "DL1ABC"
    pub.take()
    origin = Origin(Source.ROTCTLD, None, "192.168.1.20")
    event = AuditEvent(1_700_000_000.0, "tower", origin, "P 200 0", "refused: held", 10.0)
    svc.publish_audit("tower", event)
    [(topic, payload, retained)] = pub.take()
    assert (topic, retained) == ("rotor/audit", False)
    assert json.loads(payload) == {
        "time": 1_700_000_000.0,
        "rotator": "tower",
        "operator": "rotctld 192.168.1.20",
        "interface": "rotctld",
        "peer": "192.168.1.20",
        "command": "P 200 0",
        "result": "refused: held",
        "bearing_before": 10.0,
    }
    # a flood: rate-limited like the refusals (a clock that stands still: the burst alone)
    still = MqttService(Topics("rotor", {"tower": "rotor"}), pub, clock=lambda: 0.0)
    still.attach(RecordingRotator("tower", "rotorez"))
    pub.take()
    for _ in range(200):
        still.publish_audit("tower", event)
    assert len(pub.take()) == 50  # 5 x mqtt.error_events_per_s; the next says how many left


def test_refusals_and_stops_on_r_audit_never_leave_a_move_or_a_lease_change_out() -> None:
    """Rule 8 (an attack pass: some 50 refused commands, anyone's, took the rotator's whole
    budget, and the lease holder's own claim and move were left out, a ``suppressed`` count
    in their place): refusals and stops have a budget of their own."""
    svc, pub, _ = service({"tower": "rotorez"})
    still = MqttService(Topics("rotor", {"tower": "rotor"}), pub, clock=lambda: 0.0)
    still.attach(RecordingRotator("tower", "rotorez"))
    pub.take()
    neighbour = Origin(Source.ROTCTLD, None, "192.168.1.66")
    for n in range(60):
        refused = AuditEvent(1_700_000_000.0 + n, "tower", neighbour, "P 10 0", "refused: x", 1.0)
        still.publish_audit("tower", refused)
        stop = AuditEvent(1_700_000_000.0 + n, "tower", neighbour, "S", "executed", 1.0, True)
        still.publish_audit("tower", stop)
    holder = Origin(Source.MQTT, "DL1ABC")
    for command in ("claim", "target az 200", "lock ON"):
        still.publish_audit(
            "tower", AuditEvent(1_700_000_100.0, "tower", holder, command, "executed", 1.0)
        )
    published = [json.loads(payload) for _topic, payload, _retained in pub.take()]
    assert len(published) == 50 + 3  # the routine budget's burst, then the holder's three
    assert [(d["command"], d.get("suppressed")) for d in published[-3:]] == [
        ("claim", None),
        ("target az 200", None),
        ("lock ON", None),
    ]
