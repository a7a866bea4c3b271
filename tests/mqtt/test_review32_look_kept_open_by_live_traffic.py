"""Review 32: client.py rule 14 after 47a02dab. The look's timer counts every message as "the
broker answers", live ones too, not only what the broker held (a replay: the retained flag,
under MQTT 3.1.1 the broker clears it on a live one). Where the hello does not come back (the
ACL topics.py names: "without it every connect waits LOOK_TIMEOUT_S"), a broker that held
nothing but carries live traffic (a tracker's targets every few seconds, or any client that
can publish on a topic the bridge reads) keeps the look open LOOK_MAX_S, 60 s, on every
connect: the bridge gated, every target refused. The clock and the timers are the test's."""

from __future__ import annotations

import pytest

from bridge.interfaces.mqtt.client import LOOK_TIMEOUT_S
from tests.mqtt.test_client_look_timeout import LookRig


def test_live_traffic_does_not_keep_a_look_whose_hello_is_denied_open(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rig = LookRig(monkeypatch, [])
    client, clock, began = rig.client, rig.clock, rig.began
    # the broker held nothing; the hello never comes back (its ACL); a tracker's live target
    # (not retained: under MQTT 3.1.1 the broker clears the flag of a live message) at 4 s
    clock.now = began + 4.0
    client._intercepted("t/rot1/target", b"120", False)
    clock.now = began + LOOK_TIMEOUT_S
    rig.fire()
    assert client._look_lost  # nothing the broker held came for LOOK_TIMEOUT_S: timed out
