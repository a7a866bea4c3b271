"""Review 77: claim.py rule 5 takes an instance for gone only where a bridge post on this
bridge's topics says so; on its own base topic that is ``B/bridge/info``, which names the
last bridge there. A station's old computer (its instance: the default client id, made of the
host name) died outright with rotators ``tower`` and ``yagi`` (their ``R/info`` and
``R/availability`` ``online`` left retained; its last will says ``offline``). The new computer
took the base topic over (claim rule 2, nothing deleted: claim rule 3) with ``tower`` alone
(the yagi's controller away), and its own ``B/bridge/info`` replaced the old one. When the
yagi comes back, the station's next start reads the old computer's ``rotor/tower/info`` and
``rotor/yagi/info`` with ``online`` beside them, nothing there says that instance is gone, and
it is refused for good (code 2) on its own base topic, for a computer that no longer
exists."""

from __future__ import annotations

from pathlib import Path

from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def test_a_station_taken_over_from_a_dead_computer_runs_with_its_rotator_back(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "old", broker, probe) as old, Rig(tmp_path / "new", broker, probe) as new:
        old.mqtt_extra = {"keepalive_s": 5}  # (the broker sends its will 7.5 s after the kill)
        old.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
        old.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        bridge = old.start_process()
        old.ready("tower", 30)
        old.ready("yagi", 30)
        bridge.kill()
        probe.wait_value("rotor/bridge/state", "offline", 20)
        tower = new.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
        t = probe.caught_up()
        taken = new.start()  # the new computer, the yagi's controller away: taken over
        new.ready("tower", after=t)
        assert not taken.failed.is_set()
        new.stop()
        new.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})  # the yagi is back
        t = probe.caught_up()
        app = new.start()
        wait_until(
            lambda: (
                app.failed.is_set()
                or (new.status("tower").available and new.status("yagi").available)
            ),
            what="the station to run or be refused",
        )
        assert not app.failed.is_set(), app.failure
        new.ready("tower", after=t)
        probe.publish("rotor/tower/target", "90")
        tower.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
        assert not app.failed.is_set(), app.failure
