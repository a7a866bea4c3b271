"""Two MQTT clients' bursts of STOPs at one turning rotor, then a target published strictly after
them, with real parts: mosquitto, the bridge (App), an emulated Rotor-EZ on a pty (brake 1 s).

The first STOP stops the rotor; before session/stops.py rule 1 merged the others into it, each
went on the line (the rotor was taken as still moving until a reading said otherwise), the
stopped Rotor-EZ answered each with its 18-byte banner, seconds of them at 4800 baud, its
readings queued behind, and the bridge took it for silent and dropped the target published
after the bursts ("target dropped: controller not answering").
"""

from __future__ import annotations

import threading

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from tests.support.mqtt import Probe
from tests.support.rig import Rig

BRAKE = {"brake_delay_s": 1.0}


def burst(client: Probe, qos: list[int], go: threading.Barrier) -> None:
    """STOPs at these QoS, as fast as the client sends them; back once the broker has them."""
    go.wait()
    sent = [client.client.publish("rotor/stop", "", qos=q) for q in qos]
    for info in sent:
        info.wait_for_publish(10)


def test_a_target_after_two_clients_bursts_of_stops_reaches_the_controller(rig: Rig) -> None:
    emu = rig.add("tower", emu={"speed_deg_s": 20.0, **BRAKE}, **BRAKE)
    rig.start()
    rig.ready("tower")
    a, b = Probe(rig.broker.port, ""), Probe(rig.broker.port, "")
    try:
        rig.probe.publish("rotor/target", "300")
        emu.wait_for(lambda s: s.is_moving and s.az_deg > 5.0, 10)
        go = threading.Barrier(2)
        bursts = [
            threading.Thread(target=burst, args=(a, [0] * 50 + [1] * 50, go)),
            threading.Thread(target=burst, args=(b, [1] * 50, go)),
        ]
        for t in bursts:
            t.start()
        for t in bursts:
            t.join()
        stopped_at = emu.state().az_deg
        b.publish("rotor/target", "100")  # after its own STOPs, and after all of A's
        sent = emu.wait_for_frame(b"AP1100\r", timeout_s=20)
        assert sent.outcome in BEARING_OUTCOMES, sent
        emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 100) <= 3, 30)
        stops = [f for f in emu.frames("stop", "invalid") if f.data == b";"]
        assert len(stops) <= 5, len(stops)  # the express is off: the session's, merged
        errors = [m.text for m in rig.probe.on("rotor/error")]
        assert not any("not answering" in e or "dropped" in e for e in errors), errors
        assert stopped_at < 300
    finally:
        a.close()
        b.close()
