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
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

OPEN = "topic readwrite rotor/#\ntopic readwrite homeassistant/#\n"
WORDS = "rotor/bridge/fence/express"  # the express's sync topic (express.py rule 8)


@pytest.fixture
def broker_conf(tmp_path: Path) -> str:
    (tmp_path / "words.acl").write_text(OPEN)
    return f"allow_anonymous true\nacl_file {tmp_path / 'words.acl'}\nuser root"


def test_a_stop_the_express_reads_before_its_word_is_back_stops_the_rotor(
    rig: Rig, broker: Mosquitto, tmp_path: Path
) -> None:
    rig.express = True
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
    app = rig.start()
    rig.ready("tower")
    wait_until(app.express.up.is_set, 10, "the express up")
    wait_until(lambda: "tower" in app.express.held, 10, "the express holds the port")
    rig.probe.publish("rotor/target", "300")  # a long turn (145 s)
    emu.wait_for(lambda s: s.is_moving, slow(10))
    app.client._client.reconnect_delay_set(60, 60)  # the bridge's connections back late
    app.lane._client.reconnect_delay_set(60, 60)
    (tmp_path / "words.acl").write_text(f"{OPEN}topic deny {WORDS}\n")  # its words dropped
    start = broker.log.stat().st_size
    broker.restart()
    denied = f"Denied PUBLISH from {app.express.client_id}"  # its first word: it is subscribed
    wait_until(
        lambda: denied in broker.log.read_bytes()[start:].decode(errors="replace"),
        15,
        "the express back and subscribed, its word dropped",
    )
    assert not app.client.connected.is_set() and not app.lane.connected.is_set()
    assert not app.express.up.is_set()  # (it may not write: rule 8)
    operator = Probe(broker.port, "")
    try:
        assert operator.publish("rotor/stop", "STOP")  # the operator's STOP
    finally:
        operator.close()
    emu.wait_for(lambda s: not s.is_moving, slow(10))
