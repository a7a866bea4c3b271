"""Review 77: claim.py rule 5 counts an instance as gone, wherever it stands, once any bridge
post on this bridge's topics says it is not online (``standing``: ``gone`` is a set of ids).
A bridge's instance is its MQTT client id, set by hand where the broker's ACL goes by client
id (docs/mqtt.md), and it stays when the bridge's base topic changes. A station first run on
``rotor/tower`` (one rotator ``tower``), stopped, and run again on ``rotor`` with rotators
``tower`` and ``yagi`` (a second antenna), left its old ``rotor/tower/bridge/info`` and
``rotor/tower/bridge/state`` ``offline``: a second bridge on ``rotor/tower`` reads them, takes
the live station for gone, beside its live ``rotor/tower/info`` and ``online``, and runs on
the live station's rotator topic: one target turns both rotors."""

from __future__ import annotations

from pathlib import Path

from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def test_a_bridge_on_the_topic_a_live_station_once_ran_on_is_still_refused(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.base = "rotor/tower"  # the station's first layout: one rotator on rotor/tower
        tower = a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
        a.start()
        a.ready("tower")
        a.stop()
        probe.wait_value("rotor/tower/bridge/state", "offline")
        a.base = "rotor"  # then a second antenna: the same station (client id) on rotor
        a.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        t = probe.caught_up()
        first = a.start()
        a.ready("tower", after=t)
        a.ready("yagi", after=t)
        b.base = "rotor/tower"  # another station on the live station's rotator topic
        mast = b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        second = b.start()
        if not second.failed.is_set():  # refused at once is the fix; started, its rotator answers
            wait_until(
                lambda: b.status("mast").available or second.failed.is_set(),
                what="the second bridge's rotator to answer",
            )
        probe.publish("rotor/tower/target", "90")
        tower.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
        after = mast.state()
        assert (after.az_deg, after.is_moving) == (200, False), after
        assert second.failed.is_set() and not first.failed.is_set()
