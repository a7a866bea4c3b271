"""Who is turning it, end to end: a real mosquitto, the emulated Rotor-EZ on a pty, the App with
its rotctld and PST ports and Home Assistant's discovery; MQTT 5 clients that name their
operator in the user property ``operator``, as the remote companion does.

With the control lease held by one operator, every other interface's target is refused naming
the holder and the time the lease ends, the holder's turns the rotor, anyone's stop and lock ON
work; Home Assistant's release button frees it; the audit file and ``R/audit`` have every one
of these, with operator, interface and peer. A lease kept in the state file holds after a
restart and ends by itself (claims are a minute at least: that one is written to end in
seconds); its rules are proven in virtual time in tests/engine/test_operators.py. The audit
file survives a full disk.
"""

from __future__ import annotations

import http.client
import json
import logging
import socket
import time
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from bridge.runtime.audit import FREE_LINES
from tests.support import free_port, wait_until
from tests.support.console import ConsoleClient, web_section
from tests.support.mqtt import retained_snapshot
from tests.support.rig import Rig
from tests.support.udp_logger import PstClient, reserve_pst_ports, tag
from tests.support.waiting import slow

PREFIX = "homeassistant"
NODE = f"{PREFIX}/{{}}/rotorbridge_rotor_r_tower/{{}}/config"


class Operator:
    """An MQTT 5 client whose every publish carries the user property ``operator``."""

    def __init__(self, port: int, name: str) -> None:
        self.name = name
        c = paho.Client(CallbackAPIVersion.VERSION2, client_id=f"op-{name}", protocol=paho.MQTTv5)
        c.connect("127.0.0.1", port)
        c.loop_start()
        self.client = c

    def publish(self, topic: str, payload: str) -> None:
        props = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
        props.UserProperty = ("operator", self.name)
        self.client.publish(topic, payload, qos=1, properties=props).wait_for_publish(5)

    def close(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


@pytest.fixture
def operators(rig: Rig) -> Iterator[tuple[Operator, Operator]]:
    holder, other = Operator(rig.broker.port, "DL1ABC"), Operator(rig.broker.port, "G4XYZ")
    yield holder, other
    holder.close()
    other.close()


def rotctld(port: int, line: bytes) -> bytes:
    with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
        s.sendall(line)
        return s.recv(100)


def ha_configs(rig: Rig) -> dict[str, dict[str, Any]]:
    snap = retained_snapshot(rig.broker.port, f"{PREFIX}/#")
    return {t: json.loads(p) for t, p in snap.items() if t.endswith("/config") and p}


def test_the_lease_refuses_others_lets_stops_through_and_everything_is_audited(
    rig: Rig, operators: tuple[Operator, Operator]
) -> None:
    holder, other = operators
    rot_port, (pst_port, pst_replies) = free_port(), reserve_pst_ports()
    audit_path = rig.tmp / "audit.jsonl"
    rig.sections["audit_file"] = str(audit_path)
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0}, rotctld_port=rot_port,
                  pst_udp_port=pst_port)  # fmt: skip
    app = rig.start()
    rig.ready("tower")
    pst = PstClient(pst_port, replies=pst_replies)
    probe = rig.probe
    ha = ha_configs(rig)
    control_sensor = ha[NODE.format("sensor", "control")]
    release_button = ha[NODE.format("button", "release_control")]
    stop_button = ha[NODE.format("button", "stop")]
    number = ha[NODE.format("number", "target_azimuth")]
    assert control_sensor["state_topic"] == "rotor/control"

    # DL1ABC claims the rotator for 30 minutes: R/control (retained) says so
    holder.publish("rotor/control/claim", json.dumps({"operator": "DL1ABC", "minutes": 30}))
    held = probe.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] == "DL1ABC")
    until = datetime.fromisoformat(json.loads(held.text)["until"])
    ends = f"DL1ABC holds the rotator until {until.astimezone(UTC):%H:%M} UTC"

    # everyone else's target is refused, naming the holder and the end: MQTT (operator G4XYZ),
    # rotctld P (Hamlib's RPRT -9: rejected), PST, Home Assistant's number
    def refused(n: int) -> None:  # one at a time: the audit trail's order is the test's
        wait_until(lambda: len(probe.on("rotor/error")) >= n, 10, f"refusal {n}")

    def audited(n: int) -> None:  # the same, for commands sent by different clients
        wait_until(lambda: len(probe.on("rotor/audit")) >= n, 10, f"audit event {n}")

    other.publish("rotor/target", "200")
    refused(1)
    assert rotctld(rot_port, b"P 200 0\n") == b"RPRT -9\n"
    refused(2)
    pst.command(tag("AZIMUTH", 200))
    refused(3)
    probe.publish(number["command_topic"], "200.0")  # as Home Assistant sends it
    refused(4)
    refusals = [json.loads(m.text) for m in probe.on("rotor/error")]
    assert all(ends in r["message"] and "min left" in r["message"] for r in refusals)
    assert emu.state().az_deg == pytest.approx(10, abs=1) and not emu.state().is_moving
    # the other operator's claim is refused too, naming the holder
    other.publish("rotor/control/claim", json.dumps({"operator": "G4XYZ", "minutes": 5}))
    probe.wait_for("rotor/error", lambda m: "not claimed: " + ends in m.text)

    # the holder's target turns it; anyone's stop stops it (STOP is never refused)
    holder.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving, 10)
    other.publish("rotor/stop", "STOP")
    emu.wait_for(lambda s: not s.is_moving, 10)
    assert emu.state().az_deg < 290
    audited(8)
    # Home Assistant's stop button and anyone's lock ON work too
    probe.publish(stop_button["command_topic"], stop_button["payload_press"])
    audited(9)
    other.publish("rotor/lock", "ON")
    on = probe.wait_value("rotor/lock/state", "ON")
    holder.publish("rotor/lock", "OFF")
    probe.wait_value("rotor/lock/state", "OFF", after=on.t)  # (OFF at the start too)
    audited(11)

    # Home Assistant's release button frees it; then anyone may turn it
    probe.publish(release_button["command_topic"], release_button["payload_press"])
    free = lambda m: json.loads(m.text)["holder"] is None  # noqa: E731
    probe.wait_for("rotor/control", free, after=held.t)  # (free at the start too)
    other.publish("rotor/target", "60")
    emu.wait_for(lambda s: abs(s.az_deg - 60) <= 3 and not s.is_moving, 20)
    probe.wait_for("rotor/status", lambda m: json.loads(m.text)["last_operator"] == "G4XYZ")

    # the audit file and R/audit: every one of these, with operator, interface and peer
    want = [
        ("DL1ABC", "mqtt", None, "executed"),  # the claim
        ("G4XYZ", "mqtt", None, "refused"),  # target 200
        ("rotctld 127.0.0.1", "rotctld", "127.0.0.1", "refused"),
        ("pst 127.0.0.1", "pst", "127.0.0.1", "refused"),
        ("mqtt", "mqtt", None, "refused"),  # Home Assistant's number: no operator it can send
        ("G4XYZ", "mqtt", None, "refused"),  # the claim
        ("DL1ABC", "mqtt", None, "executed"),  # target 300
        ("G4XYZ", "mqtt", None, "executed"),  # stop
        ("mqtt", "mqtt", None, "executed"),  # Home Assistant's stop button
        ("G4XYZ", "mqtt", None, "executed"),  # lock ON
        ("DL1ABC", "mqtt", None, "executed"),  # lock OFF
        ("homeassistant", "mqtt", None, "executed"),  # the release button
        ("G4XYZ", "mqtt", None, "executed"),  # target 60
    ]
    wait_until(lambda: len(probe.on("rotor/audit")) >= len(want), 10, "R/audit")
    published = [json.loads(m.text) for m in probe.on("rotor/audit")]
    assert app.audit is not None
    app.audit.flush()
    filed = [json.loads(line) for line in audit_path.read_text().splitlines()]
    for events in (published, filed):
        got = [
            (e["operator"], e["interface"], e["peer"], e["result"].split(":")[0]) for e in events
        ]
        assert got == want
        assert all(e["rotator"] == "tower" and "time" in e for e in events)
        assert events[2]["result"].startswith("refused: " + ends)
        assert events[2]["command"] == "P 200 0" or "200" in events[2]["command"]
        assert events[6]["bearing_before"] == pytest.approx(10, abs=1)
    assert [m.retain for m in probe.on("rotor/audit")] == [False] * len(want)
    pst.close()


def test_a_full_disk_under_the_audit_file_is_reported_once_and_costs_nothing(rig: Rig) -> None:
    audit_path = rig.tmp / "audit.jsonl"
    audit_path.symlink_to("/dev/full")  # every write: ENOSPC, as on a full disk
    rig.sections["audit_file"] = str(audit_path)
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    app = rig.start()
    rig.ready("tower")
    probe = rig.probe
    for az in ("40", "80"):
        probe.publish("rotor/target", az)
        emu.wait_for(lambda s, az=az: abs(s.az_deg - float(az)) <= 3 and not s.is_moving, 20)
    problem = probe.wait_for("rotor/error", lambda m: json.loads(m.text)["kind"] == "audit")
    assert "No space left on device" in json.loads(problem.text)["message"]
    assert [json.loads(m.text)["kind"] for m in probe.on("rotor/error")] == ["audit"]  # once
    assert len(probe.on("rotor/audit")) == 2  # R/audit goes on
    # space again: the next line is written, without a restart
    audit_path.unlink()
    probe.publish("rotor/stop", "STOP")
    assert app.audit is not None
    wait_until(lambda: len(probe.on("rotor/audit")) == 3, 10, "the stop audited")
    app.audit.flush()
    (line,) = audit_path.read_text().splitlines()
    assert json.loads(line)["command"] == "stop 'STOP'"


def test_a_lease_kept_across_a_restart_holds_and_then_ends_by_itself(
    rig: Rig, operators: tuple[Operator, Operator]
) -> None:
    _, other = operators
    # the state file a bridge left behind, with a lease that ends a few seconds from now
    ends_unix = time.time() + 4
    lease = {"operator": "DL1ABC", "until": ends_unix}
    (rig.tmp / "state.json").write_text(json.dumps({"rotators": {"tower": {"lease": lease}}}))
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    rig.start()
    rig.ready("tower")
    probe = rig.probe
    held = probe.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] == "DL1ABC")
    other.publish("rotor/target", "200")
    probe.wait_for("rotor/error", lambda m: "DL1ABC holds the rotator until" in m.text)
    # nobody does anything: the lease ends at its time (this wait is what is under test)
    free = lambda m: json.loads(m.text)["holder"] is None  # noqa: E731
    probe.wait_for("rotor/control", free, 15, after=held.t)
    assert time.time() >= ends_unix
    ended = lambda m: json.loads(m.text)["control"] is None  # noqa: E731
    status = probe.wait_for("rotor/status", ended, after=held.t)
    assert json.loads(status.text)["control"] is None
    # its end is in the audit trail, the holder named (R/audit; the file has what it has)
    expired = probe.wait_for("rotor/audit", lambda m: "control expired" in m.text)
    doc = json.loads(expired.text)
    assert (doc["operator"], doc["interface"], doc["peer"]) == ("DL1ABC", "lease", None)
    other.publish("rotor/target", "60")
    emu.wait_for(lambda s: abs(s.az_deg - 60) <= 3 and not s.is_moving, 20)


def line(port: int, sent: bytes) -> bytes:
    """One line to a GS-232 or Easycomm port, and its answer (up to the line's end)."""
    with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
        s.sendall(sent)
        got = b""
        while not got.endswith(b"\n"):
            got += s.recv(100)
        return got


def test_every_other_interface_names_its_peer_in_the_audit_trail(
    rig: Rig, operators: tuple[Operator, Operator]
) -> None:
    """GS-232 and Easycomm on TCP, the console (its targets and its lock), PST's park and
    locator: each command refused by the lease or carried out carries its interface and the
    sender's address, and the lease claimed by one names no one else."""
    holder, _ = operators
    gs232_port, easycomm_port, web = free_port(), free_port(), web_section()
    pst_port, pst_replies = reserve_pst_ports()
    rig.sections["web"] = web
    rig.sections["station"] = {"locator": "JO62qm"}
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0}, gs232_port=gs232_port,
                  easycomm_port=easycomm_port, pst_udp_port=pst_port, park_az_deg=0)  # fmt: skip
    rig.start()
    rig.ready("tower")
    probe = rig.probe
    pst = PstClient(pst_port, replies=pst_replies)
    console = ConsoleClient(web["port"])
    console.session()

    def audited(n: int) -> None:  # one at a time: the audit trail's order is the test's
        wait_until(lambda: len(probe.on("rotor/audit")) >= n, 10, f"audit event {n}")

    holder.publish("rotor/control/claim", json.dumps({"operator": "DL1ABC", "minutes": 30}))
    audited(1)
    assert line(gs232_port, b"M200\r") == b"?>\r\n"  # refused: the GS-232 error prompt
    audited(2)
    assert line(easycomm_port, b"AZ200.0\nVE\n") == b"VErotor-bridge\n"  # refused: R/error
    audited(3)
    assert line(easycomm_port, b"PARK\nVE\n") == b"VErotor-bridge\n"
    audited(4)
    refused = console.command("tower", command="target", az=200)
    assert (refused.status, refused.doc["code"]) == (409, "leased")  # docs/console.md's code
    audited(5)
    pst.command(tag("PARK", 1))
    audited(6)
    pst.command(tag("QRA", "JN58td"))
    audited(7)
    assert console.command("tower", command="lock", on=True).status == 200  # never refused
    audited(8)
    assert console.command("tower", command="lock", on=False).status == 200
    audited(9)
    assert emu.state().az_deg == pytest.approx(10, abs=1) and not emu.state().is_moving

    local = "127.0.0.1"
    want = [
        ("DL1ABC", "mqtt", None, "executed"),  # the claim
        (f"gs232 {local}", "gs232", local, "refused"),
        (f"easycomm {local}", "easycomm", local, "refused"),
        (f"easycomm {local}", "easycomm", local, "refused"),  # park
        (f"web {local}", "web", local, "refused"),
        (f"pst {local}", "pst", local, "refused"),  # park
        (f"pst {local}", "pst", local, "refused"),  # locator
        (f"web {local}", "web", local, "executed"),  # lock ON
        (f"web {local}", "web", local, "executed"),  # lock OFF
    ]
    events = [json.loads(m.text) for m in probe.on("rotor/audit")]
    got = [(e["operator"], e["interface"], e["peer"], e["result"].split(":")[0]) for e in events]
    assert got == want
    assert all(
        "DL1ABC holds the rotator" in e["result"] for e in events if e["result"] != "executed"
    )
    assert [e["command"] for e in events[7:]] == ["lock ON", "lock OFF"]
    pst.close()


def test_under_mqtt_311_an_empty_claim_or_release_is_refused_and_the_lease_holds(
    rig: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    """Review finding: under MQTT 3.1.1 an empty message on R/control/claim or
    R/control/release was taken for the deletion of a retained one and dropped without a word
    (under MQTT 5 the claim is refused, the release carried out). It cannot be told from a
    deletion, so it is not carried out, and it is refused aloud: R/error and the log say so."""
    rig.mqtt_extra["protocol"] = "3.1.1"
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    rig.start()
    rig.ready("tower")
    probe = rig.probe
    probe.publish("rotor/control/claim", json.dumps({"operator": "DL1ABC", "minutes": 30}))
    held = probe.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] == "DL1ABC")
    with caplog.at_level(logging.INFO, logger="bridge.interfaces.mqtt.service"):
        for n, topic in enumerate(("rotor/control/claim", "rotor/control/release"), 1):
            probe.publish(topic, b"")
            wait_until(lambda n=n: len(probe.on("rotor/error")) >= n, 10, f"refusal {n}")
    refusals = [json.loads(m.text) for m in probe.on("rotor/error")]
    assert [r["command"] for r in refusals] == ["claim", "release"]
    assert all("empty payload" in r["message"] for r in refusals)
    logged = [r.getMessage() for r in caplog.records if "refused" in r.getMessage()]
    assert [line.split(":")[1] for line in logged] == [" refused claim", " refused release"]
    # nothing changed: the lease is DL1ABC's (a release after them frees it: they were heard)
    probe.publish("rotor/control/release", json.dumps({"operator": "DL1ABC"}))
    probe.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] is None, after=held.t)
    assert [json.loads(m.text)["holder"] for m in probe.on("rotor/control")][-2:] == [
        "DL1ABC",
        None,
    ]


def test_an_audit_entry_names_the_whole_command_however_it_was_padded(
    rig: Rig, operators: tuple[Operator, Operator]
) -> None:
    """A command's words were cut to their first 40 bytes in the audit trail, and JSON may be
    padded with spaces: a claim for G4XYZ sent by a plain MQTT client was audited as ``mqtt``
    executing ``claim '{"minutes": 30, ...'``, and a target that turned the rotor to 200 as
    ``target '{"azimuth": ...'``: neither who got the lease nor where the rotor went was in
    the trail. Every payload a command is taken from (256 bytes at most) is there whole."""
    _, other = operators
    audit_path = rig.tmp / "audit.jsonl"
    rig.sections["audit_file"] = str(audit_path)
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    app = rig.start()
    rig.ready("tower")
    probe = rig.probe
    claim = '{"minutes": 30,' + " " * 60 + '"operator": "G4XYZ"}'
    probe.publish("rotor/control/claim", claim)
    probe.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] == "G4XYZ")
    other.publish("rotor/target", '{"azimuth":' + " " * 60 + "200}")
    rig.arrived("tower", 200)
    assert emu.state().az_deg == pytest.approx(200, abs=3)
    wait_until(lambda: len(probe.on("rotor/audit")) >= 2, 10, "R/audit")
    published = [json.loads(m.text) for m in probe.on("rotor/audit")]
    assert app.audit is not None
    app.audit.flush()
    filed = [json.loads(line) for line in audit_path.read_text().splitlines()]
    for events in (published, filed):
        assert [(e["operator"], e["result"]) for e in events] == [
            ("mqtt", "executed"),
            ("G4XYZ", "executed"),
        ]
        assert events[0]["command"] == f"claim {claim!r}"
        assert events[1]["command"].endswith("200}'")


def test_a_logger_datagram_is_audited_whole_however_it_was_padded(rig: Rig) -> None:
    """A PstRotator datagram was audited as its first 120 characters (an N1MM one, 160), and
    PstRotator's tags the bridge does not read are let through: padded with a few, a datagram
    that turned the rotor to 200 was audited without its <AZIMUTH>. Every datagram a command
    is taken from (2048 bytes at most) is in the trail whole."""
    pst_port, pst_replies = reserve_pst_ports()
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0}, pst_udp_port=pst_port)
    rig.start()
    rig.ready("tower")
    pst = PstClient(pst_port, replies=pst_replies)
    try:
        padding = [tag(f"PAD{n}", "x" * 60) for n in range(3)]
        pst.command(*padding, tag("AZIMUTH", 200))
        rig.arrived("tower", 200)
        assert emu.state().az_deg == pytest.approx(200, abs=3)
        [event] = [json.loads(m.text) for m in rig.probe.on("rotor/audit")]
        assert (event["interface"], event["result"]) == ("pst", "executed")
        assert event["command"].endswith("<AZIMUTH>200</AZIMUTH></PST>")
    finally:
        pst.close()


def test_a_claim_in_a_name_that_shows_nothing_or_looks_like_another_is_refused(rig: Rig) -> None:
    """core/model.py ``valid_operator``: invisible format characters were refused, but not the
    Hangul filler (a name of it alone reads as blank: "ㅤ holds the rotator until ...", and
    the audit trail named an operator nobody can read) nor a zero-width joiner beside a call
    sign's letters ("DL1ABC" and a joiner: the lease another operator's, its refusals naming
    DL1ABC to DL1ABC himself). Both are refused on R/error; the lease stays free."""
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    rig.start()
    rig.ready("tower")
    probe = rig.probe
    names = ["\u3164", "DL1ABC\u200d", "\u2800\u2800"]
    for name in names:
        probe.publish("rotor/control/claim", json.dumps({"operator": name, "minutes": 30}))
    wait_until(lambda: len(probe.on("rotor/error")) >= len(names), 10, "the refusals")
    refusals = [json.loads(m.text)["message"] for m in probe.on("rotor/error")]
    assert all(r.startswith("operator must be a name") for r in refusals), refusals
    probe.publish("rotor/control/claim", json.dumps({"operator": "DL1ABC", "minutes": 30}))
    probe.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] == "DL1ABC")
    holders = [json.loads(m.text)["holder"] for m in probe.on("rotor/control")]
    assert set(holders) == {None, "DL1ABC"}


def test_a_release_naming_its_operator_twice_names_nobody_in_the_audit_trail(rig: Rig) -> None:
    """features/control/payload.py rule 2: a release's ``operator`` given twice was read as its
    last value, so the audit trail named DL1ABC for a release a reader of the payload takes for
    G4XYZ's (a claim refuses a key given twice: core/jsonkeys.py). It still releases: anyone
    may; the trail names the sender as it knows it, a plain MQTT client."""
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    rig.start()
    rig.ready("tower")
    probe = rig.probe
    probe.publish("rotor/control/claim", json.dumps({"operator": "DL1ABC", "minutes": 30}))
    held = probe.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] == "DL1ABC")
    probe.publish("rotor/control/release", '{"operator": "G4XYZ", "operator": "DL1ABC"}')
    probe.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] is None, after=held.t)
    wait_until(lambda: len(probe.on("rotor/audit")) >= 2, 10, "R/audit")
    release = json.loads(probe.on("rotor/audit")[1].text)
    assert (release["operator"], release["result"]) == ("mqtt", "executed")


def _audit_files(path: Path) -> list[dict[str, Any]]:
    """Every line of the audit file and of its rotated ones, oldest first."""
    olds = [p for p in path.parent.glob(path.name + ".*") if p.suffix[1:].isdigit()]
    ordered = [*sorted(olds, key=lambda p: -int(p.suffix[1:])), path]
    return [json.loads(line) for p in ordered if p.exists() for line in p.read_text().splitlines()]


def test_a_flood_of_stops_and_refusals_cannot_erase_who_turned_the_rotor(
    rig: Rig, operators: tuple[Operator, Operator]
) -> None:
    """runtime/audit.py rule 6, mqtt/service.py rule 8, the bridge its own process (an attack
    pass: console STOPs at 1,000 a second rolled all four audit files over in 25 s, the line
    of who turned the rotor a minute before gone; 50 refused commands left the lease holder's
    move out of R/audit). Here 1,000 STOPs over one console connection and 60 refused targets,
    each from another MQTT operator name, after the holder's claim and move: the audit files
    (four of 10,000 bytes) still have the claim and the move, the STOPs are five lines and one
    that counts the rest, with their first and last times; R/audit has the holder's next move
    as it came, no ``suppressed`` count on it, and that count line too."""
    holder, _other = operators
    audit_path = rig.tmp / "audit.jsonl"
    rig.sections["audit_file"] = str(audit_path)
    rig.sections["audit_max_bytes"] = 10_000
    web = rig.sections["web"] = web_section()
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    rig.start_process()
    rig.ready("tower")
    probe = rig.probe
    audit = lambda m: json.loads(m.text)  # noqa: E731
    holder.publish("rotor/control/claim", json.dumps({"operator": "DL1ABC", "minutes": 30}))
    holder.publish("rotor/target", "100")
    probe.wait_for("rotor/audit", lambda m: audit(m)["command"] == "target '100'")
    emu.wait_for(lambda s: abs(s.az_deg - 100) <= 3 and not s.is_moving, slow(20))

    console = ConsoleClient(web["port"])
    console.session()
    conn = http.client.HTTPConnection("127.0.0.1", web["port"], timeout=slow(10))
    head = {"Content-Type": "application/json", "X-Rotor-Token": str(console.token),
            "Origin": f"http://127.0.0.1:{web['port']}"}  # fmt: skip
    for _ in range(1000):  # one keep-alive connection, as fast as the console answers
        conn.request("POST", "/api/rotators/tower/command", b'{"command": "stop"}', head)
        assert conn.getresponse().read() == b'{"ok": true}'
    conn.close()
    crowd = Operator(rig.broker.port, "N0")
    for n in range(60):  # refused (the lease): each from a name of its own, one run each
        crowd.name = f"N{n}"
        crowd.publish("rotor/target", "300")
    crowd.close()
    holder.publish("rotor/target", "120")
    moved = probe.wait_for("rotor/audit", lambda m: audit(m)["command"] == "target '120'")
    assert audit(moved)["operator"] == "DL1ABC" and "suppressed" not in audit(moved)

    def stops() -> list[dict[str, Any]]:
        return [d for d in _audit_files(audit_path) if d["operator"] == "web 127.0.0.1"]

    # every STOP is in the file, most of them counted (a count line is said QUIET_S after the
    # last; a machine that stalls for seconds mid-flood may make two runs of it, no more)
    wait_until(lambda: sum(d.get("count", 1) for d in stops()) == 1000, 30, "the STOPs' count")
    lines = stops()
    counts = [d for d in lines if "count" in d]
    assert counts and len(lines) <= 2 * (FREE_LINES + 1)  # not 1,000
    assert all(d["command"] == "console: stop" and d["result"] == "executed" for d in lines)
    assert lines[0]["time"] < counts[0]["first"] < counts[0]["last"]
    held = [(d["command"].split()[0], d["result"]) for d in _audit_files(audit_path)
            if d["operator"] == "DL1ABC"]  # fmt: skip
    assert held == [("claim", "executed"), ("target", "executed"), ("target", "executed")]
    probe.wait_for("rotor/audit", lambda m: audit(m).get("count") == counts[0]["count"])
