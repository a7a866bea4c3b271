"""Review 67 (claim rule 5): the watched topics of a bridge on a base topic of two levels
(``shack/rotor``) include one above it, outside its own tree (``shack/bridge/info`` and
``shack/bridge/state``), and rule 5 believes any info there: its ``started`` says who is older
and its ``topics`` say what it overlaps. A client the broker's ACL keeps off the bridge's topics
(``shack/rotor/#`` denied to it), but that may write elsewhere under ``shack`` (a home-automation
user), publishes one retained info there naming ``shack/rotor`` as its rotator's topic with an
older start, and ``online``: the running bridge yields (its rotor stopped, exit 1) and every
restart is refused (code 2, not restarted by systemd). Before rule 5 that client could not touch
the bridge: a forged ``B/bridge/info`` needed write access to the bridge's own tree. A real
bridge whose rotator is ``shack/rotor`` would need that access too (it publishes there)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.claim import Instance
from tests.faults.conftest import mosquitto_password_file
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig

PASSWORDS = {"station": "st-pw-67", "automation": "ha-pw-67"}
ACL = (
    "user station\ntopic readwrite shack/rotor/#\ntopic read shack/bridge/#\n"
    "topic readwrite homeassistant/#\n"
    # the home-automation user: everything under shack but the rotor bridge's own tree
    "\nuser automation\ntopic deny shack/rotor/#\ntopic readwrite shack/#\n"
)


@pytest.fixture
def shared(tmp_path: Path) -> Iterator[tuple[Rig, Probe]]:
    (tmp_path / "shack.acl").write_text(ACL)
    passwd = mosquitto_password_file(tmp_path / "passwd", PASSWORDS)
    conf = (  # user root: read the files in the test's private temp dir (no effect unless root)
        f"user root\nallow_anonymous false\npassword_file {passwd}\n"
        f"acl_file {tmp_path / 'shack.acl'}\n"
    )
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf).start()
    station = Probe(broker.port, "shack/#", username="station", password=PASSWORDS["station"])
    automation = Probe(
        broker.port, "shack/#", username="automation", password=PASSWORDS["automation"]
    )
    try:
        with Rig(tmp_path, broker, station) as rig:
            rig.mqtt_extra = {"username": "station", "password": PASSWORDS["station"]}
            rig.base = "shack/rotor"
            yield rig, automation
    finally:
        station.close()
        automation.close()
        broker.stop()


def test_a_client_kept_off_the_bridges_topics_cannot_end_it(
    shared: tuple[Rig, Probe],
) -> None:
    rig, automation = shared
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    app = rig.start()
    rig.ready("tower", 20)
    automation.publish("shack/rotor/target", "90")  # denied: the ACL keeps it off
    forged = Instance("rotor-forged", "nowhere", 1, app.me.started_unix - 60, ("shack/rotor",))
    automation.publish("shack/bridge/info", forged.info([]), retain=True)
    automation.publish("shack/bridge/state", "online", retain=True)
    rig.probe.publish("shack/rotor/target", "200")  # the station's own operator, after them
    wait_until(
        lambda: app.failed.is_set() or abs(emu.state().az_deg - 200) <= 3,
        20,
        "the bridge to turn the rotor, or to end",
    )
    assert not app.failed.is_set(), app.failure
    assert abs(emu.state().az_deg - 200) <= 3  # not 90: the automation user's target never came
