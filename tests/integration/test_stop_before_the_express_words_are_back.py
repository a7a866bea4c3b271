"""A CI failure of review 88's proxy-restart test (tests/faults/), made deterministic: real
mosquitto, the bridge in this process, the stop express in its own and a Rotor-EZ on a real pty.

After a broker restart the stop express, on its 2 s back-off, is often the first of the bridge's
connections back. It writes no frame until a sync word it published on that connection came back
(express.py rule 8: only then can its frames be ordered against the bridge's holds). A STOP it
read in between, while neither of the bridge's own connections was subscribed (they start clean:
no copy ever comes to them), was dropped without a word: no frame, and no ``heard`` for the bridge
to carry out (rule 11), so the rotor turned on to its target. The CI run published its STOP just
after the express's SUBSCRIBE showed in the broker's log, a round trip before its word came back,
and the lanes subscribed a few milliseconds after the STOP.

The window is held open here: an ACL drops the express's sync words (its word never comes back,
so it never writes), and the bridge's two connections stay away (their back-off made long), as in
tests/integration/test_stop_express.py's ``express_alone``.

Such a stop is said ``early`` and judged by the halts the bridge's connections read alone, not by
the express's vouches (express.py rule 11): a vouch it answered at once while subscribed and not
yet writing says nothing of a stop it reads after it. The second test reads the STOP late on
purpose, behind a proxy that holds what the broker sends the express, until the stop lane, which
subscribed after the STOP, has been vouched for so.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.integration.express_gate import (
    OPEN,
    Gate,
    acl_conf,
    express_holding,
    gated_start,
    words_dropped,
)
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until


@pytest.fixture
def broker_conf(tmp_path: Path) -> str:
    return acl_conf(tmp_path, OPEN)


def test_a_stop_the_express_reads_before_its_word_is_back_stops_the_rotor(
    rig: Rig, broker: Mosquitto, tmp_path: Path
) -> None:
    rig.express = True
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
    app = rig.start()
    rig.ready("tower")
    express_holding(app)
    rig.probe.publish("rotor/target", "300")  # a long turn (145 s)
    emu.wait_for(lambda s: s.is_moving, slow(10))
    app.client._client.reconnect_delay_set(60, 60)  # the bridge's connections back late
    app.lane._client.reconnect_delay_set(60, 60)
    words_dropped(app, broker, tmp_path)
    assert not app.client.connected.is_set() and not app.lane.connected.is_set()
    assert not app.express.up.is_set()  # (it may not write: rule 8)
    operator = Probe(broker.port, "")
    try:
        assert operator.publish("rotor/stop", "STOP")  # the operator's STOP
    finally:
        operator.close()
    emu.wait_for(lambda s: not s.is_moving, slow(10))


def test_a_stop_the_express_reads_early_is_carried_out_though_a_lane_was_vouched_for_since(
    tmp_path: Path, broker: Mosquitto
) -> None:
    """The STOP is published while only the express is subscribed (its words dropped: not
    writing), and read by it late, after the stop lane subscribed and the express answered the
    lane's vouch at once. Judged by that vouch, the stop was the lane's, which never had it."""
    gate = Gate(broker.port)
    probe = Probe(broker.port, "rotor/#")  # a dashboard on the broker's own port
    try:
        with Rig(tmp_path, gate, probe) as rig:
            emu, settings, app = gated_start(
                rig, gate, emu={"start_az_deg": 10, "speed_deg_s": 2.0}
            )
            probe.publish("rotor/target", "300")  # a long turn (145 s)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            gate.refused |= {settings.effective_client_id(), lane_client_id(settings)}
            words_dropped(app, broker, tmp_path)
            assert not app.client.connected.is_set() and not app.lane.connected.is_set()
            gate.hold(True)  # what the broker sends the express waits at the gate
            assert probe.publish("rotor/stop", "STOP")  # the operator's STOP, for it alone
            gate.refused.discard(lane_client_id(settings))  # the stop lane back after it

            def vouched() -> bool:  # the lane's subscription answered for, at once
                since = app.express.vouched("lane")
                return since is not None and app.lane.heard_since(since)

            wait_until(vouched, 15, "the stop lane back and vouched for")
            gate.hold(False)  # the express reads the STOP now
            emu.wait_for(lambda s: not s.is_moving, slow(10))
    finally:
        probe.close()
        gate.close()
