"""Review 82: claim.py rule 5 says a bridge's own instance never refuses it ("a restart of this
installation"), but the instance is the default client id, a hash of the host name, the state
file's path and the base topic (settings/mqtt.py ``effective_client_id``). A station ran on
``rotor`` with rotators ``tower`` and ``yagi`` and lost power (killed outright: its rotators'
``R/availability`` stay ``online``, its last will says ``offline`` on ``rotor/bridge/state``).
The yagi came down, and the operator gave the station the base topic ``rotor/tower``, so that
the tower, now its one rotator, keeps the topics every flow and dashboard already uses. The
station's next start reads its own old ``rotor/tower/info``, stamped with the instance it had
on ``rotor``, and ``online`` beside it: another live bridge, it says, and refuses (code 2) on
its own rotator's topic for good; no bridge post under ``rotor/tower`` says that instance is
gone (its last will lies on ``rotor/bridge/state``, above), and the refusal's advice, start
that bridge and stop it, names a configuration that no longer exists."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bridge.emulators.pty import EmulatedPort
from tests.support import Probe, slow, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import retained_snapshot
from tests.support.rig import Rig


def test_a_station_given_its_one_rotators_topic_as_base_runs_after_a_crash(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "station", broker, probe) as station:
        tower = tower_and_yagi_station_killed(station, broker, probe)
        # the yagi is down for good; the tower keeps its topics, now the base topic
        runs_on_the_towers_topic_alone(station, probe, tower)


def tower_and_yagi_station_killed(
    station: Rig, broker: Mosquitto, probe: Probe
) -> EmulatedPort[Any]:
    """``station`` on ``rotor`` with rotators ``tower`` and ``yagi`` (the default client id),
    run as a process and killed outright; its tower's ``online`` left retained. The tower's
    emulator."""
    # the default client id (made of host, state file and base topic), as installed
    station.mqtt_extra = {"client_id": "", "keepalive_s": 5}
    tower = station.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
    station.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
    bridge = station.start_process()
    station.ready("tower", slow(30))
    station.ready("yagi", slow(30))
    bridge.kill()  # a power cut
    probe.wait_value("rotor/bridge/state", "offline", slow(20))
    held = retained_snapshot(broker.port, "rotor/tower/availability")
    assert held == {"rotor/tower/availability": b"online"}, held
    return tower


def runs_on_the_towers_topic_alone(station: Rig, probe: Probe, tower: EmulatedPort[Any]) -> None:
    """``station`` started again with the tower alone and ``rotor/tower`` as its base topic:
    it must run, and a target turns the tower."""
    station.rotators[:] = [r for r in station.rotators if r["id"] == "tower"]
    del station.lines["yagi"]
    station.base = "rotor/tower"
    t = probe.caught_up()
    app = station.start()
    wait_until(
        lambda: app.failed.is_set() or station.status("tower").available,
        what="the station to run or be refused",
    )
    assert not app.failed.is_set(), app.failure
    station.ready("tower", after=t)
    probe.publish("rotor/tower/target", "90")
    tower.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, slow(15))
