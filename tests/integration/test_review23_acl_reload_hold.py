"""A guard: 0785d896 did what is said below, and was reverted (6129c849).

Cold review 23: lastword.py rule 7 says it: "An ACL changed under a live connection to deny
both topics is seen by no probe: a lane hold up then lasts until the connection drops". Since
0785d896 nothing else ends it (the main connection's copy of the STOP no longer does, rule 2).
mosquitto reloads its ACL file on SIGHUP and keeps the connections: an administrator who
tightens B/bridge/# to the bridge's user leaves a bridge that, at the first STOP on the stop
connection, refuses every MQTT target for that rotator ("published before a STOP ... send it
again", sent again refused again) for as long as the connection lasts, hours or days; the
rotator is stuck for MQTT until the bridge or the broker is restarted. At cb3b3403 the main
connection's copy of the STOP ended the hold and the next target turned the rotor.
"""

from __future__ import annotations

import time
from pathlib import Path

from tests.integration.test_broker_acl import acl_rig
from tests.support.waiting import wait_until


def test_a_lane_stop_after_an_acl_reload_denying_the_markers_does_not_refuse_targets_for_ever(
    tmp_path: Path,
) -> None:
    with acl_rig(tmp_path, "topic readwrite rotor/#\n") as (rig, probe):
        emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0})
        app = rig.start()
        rig.ready("tower")
        wait_until(app.lane.connected.is_set, 10, "the lane is up")
        deny = "topic readwrite rotor/#\ntopic deny rotor/bridge/fence\n"
        deny += "topic deny rotor/bridge/hello\n"
        (tmp_path / "acl").write_text(deny)
        rig.broker.reload()
        time.sleep(1.0)  # (mosquitto reloads on SIGHUP, the connections kept)
        probe.publish("rotor/target", "200")
        emu.wait_for(lambda s: s.is_moving, 10)
        probe.publish("rotor/stop", "")  # the operator's STOP, on both connections
        emu.wait_for(lambda s: not s.is_moving, 10)
        time.sleep(3.0)  # long after the STOP, nothing behind on either connection
        t = time.monotonic()
        for _ in range(20):  # 20 s of a target sent again and again, as R/error says
            probe.publish("rotor/target", "300")
            time.sleep(1.0)
            if emu.state().is_moving or abs(emu.state().az_deg - 300) <= 3:
                break
        refused = [m for m in probe.on("rotor/error") if m.t >= t and b"300" in m.payload]
        assert emu.state().is_moving or abs(emu.state().az_deg - 300) <= 3, (
            f"20 s of targets published seconds after the STOP, {len(refused)} refusals said "
            f"(R/error is rate-limited), none taken; the hold up: {app.mqtt._word.holding}"
        )
