"""Attack 23, with real mosquitto and the stop express's real process: a broker away for more
than START_WAIT_S (10 s) has the bridge log, at ERROR, "the stop express did not come up within
10 s", and hands it to ``B/bridge/info``'s problems, though the express had been up for the
whole run and only its broker went away; once the broker is back the log says "stop express
up ... (63.61 s)", counted from the child's first start. Someone reading the journal after a
broker restart is sent looking for a failed start of the express (interfaces/mqtt/express.py
rule 6 says "an express not up within START_WAIT_S": its connection's end, rule 8's ``down``,
is taken for a start).
"""

from __future__ import annotations

import logging
import time

import pytest

from bridge.interfaces.mqtt.express import START_WAIT_S
from tests.faults.conftest import Rig
from tests.support import wait_until

DOWN_S = START_WAIT_S + 2.0  # the broker away: the fault's length (not a deadline)


def test_a_broker_outage_is_not_said_as_a_stop_express_that_did_not_start(
    rig: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    rig.express = True  # the default
    rig.add("tower", "rotorez", emu={"start_az_deg": 10})
    with caplog.at_level(logging.INFO, logger="bridge.interfaces.mqtt.express"):
        rig.start()
        rig.ready("tower")
        wait_until(lambda: "stop express up" in caplog.text, 20, "the express up")
        up_once = caplog.text.count("stop express up")
        rig.broker.stop()
        time.sleep(DOWN_S)  # the broker away: the fault's length (not a deadline)
        rig.broker.start()
        wait_until(
            lambda: caplog.text.count("stop express up") > up_once, 60, "the express back up"
        )
    said = [r.getMessage() for r in caplog.records if "did not come up" in r.getMessage()]
    assert not said, said
