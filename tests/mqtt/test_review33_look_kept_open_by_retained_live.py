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

import threading
from collections.abc import Callable
from typing import Any

import pytest

import bridge.interfaces.mqtt.client as client_module
from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.client import LOOK_TIMEOUT_S, MqttClient
from bridge.settings import MqttSettings


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def monotonic(self) -> float:
        return self.now


class Timers:
    """``threading`` as the client sees it, but a Timer is only noted (delay, function, args)."""

    def __init__(self) -> None:
        self.armed: list[tuple[float, Callable[..., None], tuple[Any, ...]]] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(threading, name)

    def Timer(self, delay: float, fn: Callable[..., None], args: tuple[Any, ...] = ()) -> Any:  # noqa: N802
        armed = self.armed

        class Noted:
            daemon = False

            def start(self) -> None:
                armed.append((delay, fn, args))

        return Noted()


@pytest.mark.xfail(
    strict=True,
    reason="review 33: a live command published retained (retain-as-published) keeps the look open",
)
def test_a_live_command_published_retained_does_not_keep_a_look_whose_hello_is_denied_open(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    clock, timers = Clock(), Timers()
    monkeypatch.setattr(client_module, "time", clock)
    monkeypatch.setattr(client_module, "threading", timers)
    client = MqttClient(
        MqttSettings(port=1, base_topic="t", client_id="look-under-test"),
        will_topic="t/bridge/state",
        subscriptions=["t/rot1/target"],
        on_message=lambda *a: None,
        claim=Claim(Instance.me("look-under-test"), "t", "t/bridge/info", "t/bridge/hello"),
    )
    look = client._look
    assert look is not None
    n = int(look.begin().split()[-1])
    began = clock.now
    client._look_heard = 0.0  # (as a connect does)
    client._arm_look(n, began, LOOK_TIMEOUT_S)
    # the broker held nothing; the hello never comes back (its ACL); a tracker set to retain
    # publishes its target at 4 s, live: retain-as-published hands it on with the flag set
    clock.now = began + 4.0
    client._intercepted("t/rot1/target", b"120", True)
    clock.now = began + LOOK_TIMEOUT_S
    _delay, fn, args = timers.armed[-1]
    fn(*args)
    assert client._look_lost  # nothing the broker held came for LOOK_TIMEOUT_S: timed out
