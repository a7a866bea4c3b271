"""Review 33: client.py rule 14 after 1f838d42. The look's quiet time now counts "retained"
messages only, taking the retain flag for "the broker hands over what it held". The command
topics are subscribed with retain-as-published (connection.py ``command_filters``: ``live``),
so under MQTT 5 a live command a client publishes with the retain flag (a Home Assistant
automation or a tracker set to retain, every one refused by service.py rule 1 and said on the
error topic) comes with the flag set, as a replay does: a look whose hello is denied (its ACL)
is kept open by it, LOOK_MAX_S, 60 s, on every connect, the bridge gated and every other
client's targets refused meanwhile, 1f838d42's own symptom. The clock and the timers are the
test's."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.client import LOOK_TIMEOUT_S
from tests.mqtt.test_client_look_timeout import LookRig


def test_a_live_command_published_retained_does_not_keep_a_look_whose_hello_is_denied_open(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rig = LookRig(monkeypatch, ["t/rot1/target"])
    client, clock, began = rig.client, rig.clock, rig.began
    # the broker held nothing; the hello never comes back (its ACL); a tracker set to retain
    # publishes its target at 4 s, live: retain-as-published hands it on with the flag set
    clock.now = began + 4.0
    client._intercepted("t/rot1/target", b"120", True)
    clock.now = began + LOOK_TIMEOUT_S
    rig.fire()
    assert client._look_lost  # nothing the broker held came for LOOK_TIMEOUT_S: timed out
