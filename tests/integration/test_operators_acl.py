"""The control lease on a broker with logins and an access list (docs/deployment.md, "A shared
station"): a station user for the bridge, a user per operator who reads the state and publishes
commands; the lease's lines as the page prints them. An operator claims and releases; no
operator can fake the bridge's retained record of the lease."""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.faults.conftest import mosquitto_password_file
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.process import ROOT
from tests.support.rig import Rig
from tests.support.waiting import wait_until

PASSWORDS = {"station": "station-S3cret", "dl1abc": "dl1abc-S3cret", "g4xyz": "g4xyz-S3cret"}
# what every operator may do besides the lease (the access list of "Operate from anywhere")
OPERATOR_LINES = """topic read rotor/#
topic write rotor/target
topic write rotor/stop
topic write rotor/park
topic write rotor/lock
"""


def documented_lease_lines() -> str:
    text = (ROOT / "docs" / "deployment.md").read_text()
    found = re.search(r"```text\n(# the control lease, for each operator\n.*?)```", text, re.S)
    assert found, "docs/deployment.md has no block of the lease's ACL lines"
    return found.group(1)


@pytest.fixture
def station(tmp_path: Path) -> Iterator[tuple[Rig, dict[str, Probe]]]:
    acl = "user station\ntopic readwrite rotor/#\ntopic readwrite homeassistant/#\n"
    for user in ("dl1abc", "g4xyz"):
        acl += f"\nuser {user}\n{OPERATOR_LINES}{documented_lease_lines()}"
    (tmp_path / "rotor.acl").write_text(acl)
    passwd = mosquitto_password_file(tmp_path / "passwd", PASSWORDS)
    conf = (  # user root: read the files in the test's private temp dir (no effect unless root)
        f"user root\nallow_anonymous false\npassword_file {passwd}\n"
        f"acl_file {tmp_path / 'rotor.acl'}\n"
    )
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf).start()
    logins = {
        u: Probe(broker.port, "rotor/#", username=u, password=p) for u, p in PASSWORDS.items()
    }
    try:
        with Rig(tmp_path, broker, logins["station"]) as rig:
            rig.mqtt_extra = {"username": "station", "password": PASSWORDS["station"]}
            rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
            rig.start()
            rig.ready("tower", 20)
            yield rig, logins
    finally:
        for probe in logins.values():
            probe.close()
        broker.stop()


def holder(probe: Probe) -> object:
    last = probe.last("rotor/control")
    return None if last is None else json.loads(last.text)["holder"]


def test_operators_claim_and_release_and_cannot_fake_the_lease(
    station: tuple[Rig, dict[str, Probe]],
) -> None:
    rig, logins = station
    dl1abc, g4xyz = logins["dl1abc"], logins["g4xyz"]
    dl1abc.publish("rotor/control/claim", json.dumps({"operator": "DL1ABC", "minutes": 30}))
    held = g4xyz.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] == "DL1ABC")
    # the bridge's retained record is the station user's: an operator's write is dropped
    g4xyz.publish("rotor/control", '{"holder": "G4XYZ", "until": null}', retain=True)
    g4xyz.publish("rotor/target", "200")  # refused: a round trip through the bridge after it
    for login in (g4xyz, dl1abc, rig.probe):  # each has what the broker sent before the error
        login.wait_for("rotor/error", lambda m: "DL1ABC holds the rotator" in m.text)
    assert holder(g4xyz) == "DL1ABC" and holder(rig.probe) == "DL1ABC"
    forged = [m for m in dl1abc.on("rotor/control") if b"G4XYZ" in m.payload]
    assert forged == []  # the broker dropped it: nobody ever saw it
    fresh = Probe(rig.broker.port, "rotor/control", username="g4xyz", password=PASSWORDS["g4xyz"])
    try:
        wait_until(lambda: fresh.last("rotor/control") is not None, 10, "the retained record")
        assert holder(fresh) == "DL1ABC"  # what the broker keeps is the bridge's
    finally:
        fresh.close()
    # anyone of them may release it (coordination, not security)
    g4xyz.publish("rotor/control/release", "")
    free = lambda m: json.loads(m.text)["holder"] is None  # noqa: E731
    dl1abc.wait_for("rotor/control", free, after=held.t)  # (free at the start too)
    g4xyz.publish("rotor/target", "60")
    rig.emus["tower"].wait_for(lambda s: abs(s.az_deg - 60) <= 3 and not s.is_moving, 20)
