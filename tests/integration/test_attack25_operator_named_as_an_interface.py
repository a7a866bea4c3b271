"""Attack 25: an MQTT sender names itself as another interface's sender, and the audit trail and
R/status write that name as who turned the rotor.

Without a name of their own, senders are named by their interface and address: a rotctld client
at 192.168.1.20 is ``rotctld 192.168.1.20`` in the audit's ``operator``, in R/status's
``last_operator``. Such a name is no operator's (runtime/lease.py rule 1: "an interface's name
... is no operator's: it stands for everyone who sends without a name there"), and the lease
refuses a claim in it. The MQTT user property ``operator`` is taken all the same
(interfaces/mqtt/service.py ``origin``: any valid_operator text): a client publishing
``R/target`` with ``operator: rotctld 192.168.1.20`` turns the rotor and the audit line's
``operator``, as R/status's ``last_operator``, names the logger PC at 192.168.1.20, which sent
nothing. (The line's ``interface`` still says mqtt: a reader who goes by ``operator``, the
console and Home Assistant's "last operator", are told the wrong sender.)

Real mosquitto, the Rotor-EZ emulator on a pty through pyserial, the App in-process.
"""

from __future__ import annotations

import json

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from tests.support import wait_until
from tests.support.rig import Rig
from tests.support.waiting import slow

FORGED = "rotctld 192.168.1.20"  # how the bridge names a rotctld client there


def _lines(rig: Rig) -> list[dict[str, object]]:
    assert rig.app is not None
    rig.app.audit.flush()
    path = rig.tmp / "audit.jsonl"
    return [json.loads(x) for x in path.read_text().splitlines()] if path.exists() else []


def audited_target(rig: Rig, client_id: str, operator: str) -> dict[str, object]:
    """``tower`` started with an audit file; an MQTT client ``client_id`` publishes
    ``rotor/target`` 40 with the user property ``operator``: the audit line of that target."""
    rig.sections["audit_file"] = str(rig.tmp / "audit.jsonl")
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    rig.start()
    rig.ready("tower")
    c = paho.Client(CallbackAPIVersion.VERSION2, client_id=client_id, protocol=paho.MQTTv5)
    c.connect("127.0.0.1", rig.broker.port)
    c.loop_start()
    try:
        props = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
        props.UserProperty = ("operator", operator)
        c.publish("rotor/target", "40", qos=1, properties=props).wait_for_publish(slow(5))
        wait_until(
            lambda: any(e["command"] == "target '40'" for e in _lines(rig)),
            slow(10),
            "the target in the audit file",
        )
    finally:
        c.loop_stop()
        c.disconnect()
    line = next(e for e in _lines(rig) if e["command"] == "target '40'")
    return line


def test_an_interfaces_name_is_no_operator_in_the_audit_trail(rig: Rig) -> None:
    line = audited_target(rig, "forger", FORGED)
    status = json.loads(
        rig.probe.wait_for(
            "rotor/status", lambda m: json.loads(m.payload)["last_operator"] is not None
        ).payload
    )
    assert line["operator"] != FORGED and status["last_operator"] != FORGED, (
        f"an MQTT client named itself {FORGED!r}: audit line {line}, R/status last_operator "
        f"{status['last_operator']!r}"
    )
