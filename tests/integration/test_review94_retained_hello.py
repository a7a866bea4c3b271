"""Review 94: look.py rule 14's hello ends the first look when it comes back: the broker sends
a subscription's retained messages before anything published after it, so what arrives before
the hello is all it held. The hello is never retained (it "names the instance and the look's
number, so a late hello of an earlier look, or another bridge's, ends nothing"), but a
retained message on ``B/bridge/hello`` is taken for it all the same (client.py ``_look_saw``
reads no retain flag): the broker replays it as it answers the look's own SUBSCRIBE, whose
first filter is the hello's, before the retained values of the posts read for the look alone
(claim.py rule 5: the bridge info and state above the base topic). With the broker holding
the bridge's rotator's lock state (it ran there before: nothing to probe) and no stamp asking
for a vouch read (no second hello), that replay ends the look at once. The instance id is the
client id, and the first look of every process is number 1: one retained ``"<client id> 1"``
on ``rotor/tower/bridge/hello`` (a topic of the bridge's own) makes bridge B on
``rotor/tower`` judge before ``rotor/bridge/info`` and ``online`` arrive, and it takes live
bridge A on ``rotor``, whose tower's controller is off (``rotor/tower/availability``
``offline``, review 77), for gone: B runs, and once the controller is switched on one target
on ``rotor/tower/target`` turns both rotors, at every start of B while the message stays.
Without the retained hello the same B is refused (tests/integration/
test_review77_controller_off.py). Fixed: a retained message on the hello topic ends no look (the
bridge never publishes one retained there), and is said once in the log, with how to delete it."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.integration.test_attack18_base_topic_under_a_rotator import (
    station_on_rotor,
    station_on_tower,
)
from tests.integration.test_review77_controller_off import (
    second_bridge_never_turns_with_the_tower,
)
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def test_a_retained_hello_does_not_end_the_first_look(
    tmp_path: Path, broker: Mosquitto, probe: Probe, caplog: pytest.LogCaptureFixture
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        tower = station_on_rotor(a)
        tower.set_silent(True)  # the tower's controller switched off
        first = a.start()
        a.ready("yagi")
        probe.wait_value("rotor/tower/availability", "offline")
        probe.wait_value("rotor/tower/lock/state", "OFF")  # (B's witness: held, not probed)
        mast = station_on_tower(b)
        client_id = b.config()["mqtt"]["client_id"]
        assert probe.publish("rotor/tower/bridge/hello", f"{client_id} 1", retain=True)
        second_bridge_never_turns_with_the_tower(probe, first, b, tower, mast)
    said = [r.getMessage() for r in caplog.records if "forged or left-over" in r.getMessage()]
    assert len(said) == 1, said  # (once: and how to delete it)
    assert "mosquitto_pub -t 'rotor/tower/bridge/hello' -r -n" in said[0]
