"""Review 85: claim rule 5 says what stands above the base topic (``A/bridge/info``,
``A/bridge/state``) "only vouches, never refuses nor takes anything for gone by itself, so a
client kept off our topics forges nothing". A station X on ``rotor`` (rotators ``tower`` and
``yagi``) is taken down for good, cleanly: its ``rotor/tower/info`` (stamped X) and
``offline`` stay retained, as does its ``rotor/bridge/info`` and ``offline``. A new station Y
on ``rotor/tower`` takes the leftover for a gone bridge's and runs. One retained ``online``
on ``rotor/bridge/state``, outside Y's topics (a client that may write the topics above, not
Y's), vouches for X's leftover, and Y is refused at its start, code 2, for as long as that
message stays: "another bridge runs on this bridge's topics", naming X, which is gone."""

from __future__ import annotations

from pathlib import Path

from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def test_a_forged_state_above_never_refuses_a_station_by_a_gone_bridges_leftover(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "x", broker, probe) as x, Rig(tmp_path / "y", broker, probe) as y:
        x.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
        x.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        x.start()
        x.ready("tower")
        x.ready("yagi")
        x.stop()  # X taken down for good, cleanly
        probe.wait_value("rotor/bridge/state", "offline")
        probe.publish("rotor/bridge/state", "online", retain=True)  # the forged word above
        y.base = "rotor/tower"
        mast = y.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        app = y.start()
        wait_until(
            lambda: app.failed.is_set() or y.status("mast").available,
            what="the station on rotor/tower to run or be refused",
        )
        assert not app.failed.is_set(), app.failure
        probe.publish("rotor/tower/target", "90")
        mast.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
