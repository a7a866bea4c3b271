"""Review 114: d8136809 lets a move the main connection read and the rotator "took" order the
stop express's ``early`` STOP before it (halts.py ``read_since``, ``moved``): such a STOP is
dropped, as older than the move. "Took" is ``submit`` returning; but a track start for a
satellite the bridge must look up in the TLE file is taken by the judge and refused only by
the session after its look-up, and until then, and after its refusal, it ends nothing: the
turn published before the STOP goes on. The STOP only the express read (after a broker
restart, its sync word not yet back) is dropped all the same, and the rotor turns on to the
old target: the promise of the same commit's refused-target counterpart (a move the rotator
did not take leaves the old turn on, and the STOP is carried out) broken by a move refused one
step later.

Real mosquitto, the bridge in this process, the express in its own, a Rotor-EZ on a real pty;
the gate of tests/integration/test_stop_before_the_express_words_are_back.py, as in
tests/integration/test_review108_early_stop_stops_a_newer_target.py.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.interfaces.mqtt.express import express_client_id
from bridge.interfaces.mqtt.lane import lane_client_id
from tests.integration.express_gate import OPEN, WORDS, Gate
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until


@pytest.fixture
def broker_conf(tmp_path: Path) -> str:
    (tmp_path / "words.acl").write_text(OPEN)
    return f"allow_anonymous true\nacl_file {tmp_path / 'words.acl'}\nuser root"


def test_an_early_stop_is_carried_out_after_a_track_start_whose_lookup_is_refused(
    tmp_path: Path, broker: Mosquitto
) -> None:
    gate = Gate(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    tle = tmp_path / "sats.tle"
    tle.write_text("")  # a TLE file with no satellite in it: every name is unknown
    try:
        with Rig(tmp_path, gate, probe) as rig:
            rig.express = True
            rig.sections["station"] = {"latitude_deg": 50.0, "longitude_deg": 10.0}
            rig.sections["tracking"] = {"tle_file": str(tle)}
            emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            settings = rig.settings.mqtt
            gate.held_id = express_client_id(settings)
            app = rig.start()
            rig.ready("tower")
            wait_until(app.express.up.is_set, 10, "the express up")
            wait_until(lambda: "tower" in app.express.held, 10, "the express holds the port")
            assert probe.publish("rotor/target", "300")  # a long turn (145 s)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            main_and_lane = {settings.effective_client_id(), lane_client_id(settings)}
            gate.refused |= main_and_lane  # the bridge's connections back after the STOP
            (tmp_path / "words.acl").write_text(f"{OPEN}topic deny {WORDS}\n")
            start = broker.log.stat().st_size
            broker.restart()
            denied = f"Denied PUBLISH from {app.express.client_id}"
            wait_until(
                lambda: denied in broker.log.read_bytes()[start:].decode(errors="replace"),
                15,
                "the express back and subscribed, its word dropped",
            )
            gate.hold(True)  # the express reads what the broker sends it late
            assert probe.publish("rotor/stop", "STOP")  # 1: the operator's STOP
            gate.refused -= main_and_lane
            wait_until(
                lambda: (
                    app.client.subscribed_since is not None
                    and app.lane.subscribed_since is not None
                ),
                15,
                "the bridge's connections back and subscribed",
            )
            mark = probe.mark()
            assert probe.publish("rotor/track", "NO SUCH SAT")  # 2: a track start, refused

            def refused() -> bool:
                return any(m.topic == "rotor/error" for m in probe.messages[mark:])

            wait_until(refused, 10, "the track start refused after its look-up")
            assert emu.wait_for(lambda s: True).is_moving  # (the turn to 300 goes on)
            gate.hold(False)  # the express reads the STOP now (early: no frame)
            emu.wait_for(lambda s: not s.is_moving, slow(10))
    finally:
        probe.close()
        gate.close()
