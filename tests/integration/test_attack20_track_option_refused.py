"""Attack 20: Home Assistant's track select offers a satellite the bridge then refuses. The
select's options are the TLE file's names (homeassistant/info.py ``track_options``), any
length; ``R/track`` takes a name of at most 64 characters (payloads.py ``parse_track``). A
file whose name line is longer (a hand-made TLE file naming its satellite in words, or a
Space-Track 3LE "0 ..." line with a comment) puts that satellite in the select, and picking
it gets "track: a name of at most 64 printable characters" on R/error: an entity whose
command Home Assistant sends is refused, the satellite cannot be tracked from the dashboard
that offers it. Real mosquitto, an MD-01 emulator on a real pty; asserted: the retained
discovery config, R/error and the retained R/tracking."""

from __future__ import annotations

import json
import time
from pathlib import Path

from tests.integration.test_tracking_bridge import (
    BERLIN,
    QUICK_BRIDGE,
    QUICK_EMU,
    SAT_EPOCH,
    Wall,
    a_pass_ahead,
    start,
)
from tests.support.mqtt import retained_snapshot
from tests.support.rig import Rig

LONG_NAME = "AMSAT-OSCAR 7 (AO-7) - the oldest amateur satellite still heard, launched 1974"


def test_every_satellite_the_track_select_offers_can_be_tracked(rig: Rig, tmp_path: Path) -> None:
    assert len(LONG_NAME) > 64
    wall = Wall(SAT_EPOCH)
    line1, line2, _aos, _los = a_pass_ahead(wall())
    tle_file = tmp_path / "amateur.txt"
    tle_file.write_text(f"{LONG_NAME}\n{line1}\n{line2}\n")
    rig.add("dish", model="md01", emu=QUICK_EMU, **QUICK_BRIDGE)
    start(rig, BERLIN, tle_file, wall=wall)
    ha = retained_snapshot(rig.broker.port, "homeassistant/#")
    select = json.loads(ha["homeassistant/select/rotorbridge_rotor_r_dish/track/config"])
    offered = [o for o in select["options"] if o not in ("off", "sun", "moon")]
    assert offered, select["options"]  # the file's satellite, whatever form the select gives it

    t = time.monotonic()
    for option in offered:
        rig.probe.publish(select["command_topic"], option)  # as Home Assistant sends it
    # a barrier on the same connection: the tracks were judged before this refusal is said
    rig.probe.publish("rotor/target", "north")
    rig.probe.wait_for("rotor/error", lambda m: b"north" in m.payload, after=t)
    refused = [
        json.loads(m.payload)["message"]
        for m in rig.probe.on("rotor/error")
        if json.loads(m.payload).get("command", "").startswith("track")
    ]
    assert not refused, (offered, refused)
