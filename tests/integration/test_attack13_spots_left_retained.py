"""Attack 13: ``B/spots`` is retained. A bridge run with ``[dxcluster]`` leaves its last spots
there; started again with the DX cluster taken out of its configuration, the bridge never
publishes ``B/spots`` again, and its first look, which deletes what a removed rotator or a
feature a rotator no longer has left retained (interfaces/mqtt/stale.py), leaves the spots
alone: every dashboard, script or Node-RED flow that reads them (docs/mqtt.md) was shown, for
good, the spots of the day the cluster was switched off, as if they were current. Fixed: the
first look deletes a station feature's topics while the feature is off (stale.py rule 6).

Real parts: mosquitto, the bridge in-process on an emulated Rotor-EZ on a pty, a fake cluster
node on loopback TCP (tests/support/cluster.py) for the first run."""

from __future__ import annotations

import json
from pathlib import Path

from tests.dxcluster.cty_sample import CTY_DAT
from tests.support import retained_snapshot, wait_until
from tests.support.clock import RunningWall
from tests.support.cluster import FakeCluster, Session
from tests.support.rig import Rig
from tests.support.waiting import slow

SPOT = b"DX de EA5WU:     14025.0  JA1ABC       cq up 2                        1829Z\r\n"
GHOST = "rotor/ghost/availability"  # a removed rotator's, deleted by the first look (stale.py)


def test_the_spots_a_run_with_the_dx_cluster_left_are_gone_once_it_is_taken_out(
    rig: Rig, tmp_path: Path
) -> None:
    def node(s: Session) -> None:
        s.send(b"login: ")
        cluster.logins.append(s.read_line())
        s.send(SPOT)
        cluster.done.wait(slow(60))

    cluster = FakeCluster([node])
    cty = tmp_path / "cty.dat"
    cty.write_text(CTY_DAT)
    station = {"locator": "JO62QM"}
    rig.add("tower", emu={"start_az_deg": 10})
    rig.sections = {
        "station": station,
        "dxcluster": {
            "enabled": True,
            "host": "127.0.0.1",
            "port": cluster.port,
            "login": "g4abc",
            "cty_file": str(cty),
        },
    }
    rig.wall = RunningWall("1830")  # the spot's time is live (dxcluster/book.py rule 2)
    try:
        rig.start()
        rig.ready("tower")
        rig.probe.wait_for("rotor/spots", lambda m: b"JA1ABC" in m.payload, 20)
        rig.stop()
    finally:
        cluster.close()

    rig.sections = {"station": station}  # the DX cluster switched off
    rig.probe.publish(GHOST, "online", retain=True)
    rig.start()
    rig.ready("tower")
    wait_until(
        lambda: GHOST not in retained_snapshot(rig.broker_port, "rotor/#"),
        20,
        "the first look's deletions",
    )
    left = retained_snapshot(rig.broker_port, "rotor/#").get("rotor/spots")
    shown = [s["call"] for s in json.loads(left)["spots"]] if left else []
    assert shown == [], f"B/spots still shows {shown} with no DX cluster configured"
