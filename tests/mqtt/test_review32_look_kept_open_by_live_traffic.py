"""Review 32: client.py rule 14 after 47a02dab. The look's timer counts every message as "the
broker answers", live ones too, not only what the broker held (a replay: the retained flag,
under MQTT 3.1.1 the broker clears it on a live one). Where the hello does not come back (the
ACL topics.py names: "without it every connect waits LOOK_TIMEOUT_S"), a broker that held
nothing but carries live traffic (a tracker's targets every few seconds, or any client that
can publish on a topic the bridge reads) keeps the look open LOOK_MAX_S, 60 s, on every
connect: the bridge gated, every target refused. The clock and the timers are the test's."""

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


def test_live_traffic_does_not_keep_a_look_whose_hello_is_denied_open(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    clock, timers = Clock(), Timers()
    monkeypatch.setattr(client_module, "time", clock)
    monkeypatch.setattr(client_module, "threading", timers)
    client = MqttClient(
        MqttSettings(port=1, base_topic="t", client_id="look-under-test"),
        will_topic="t/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        claim=Claim(Instance.me("look-under-test"), "t", "t/bridge/info", "t/bridge/hello"),
    )
    look = client._look
    assert look is not None
    n = int(look.begin().split()[-1])
    began = clock.now
    client._look_heard = 0.0  # (as a connect does)
    client._arm_look(n, began, LOOK_TIMEOUT_S)
    # the broker held nothing; the hello never comes back (its ACL); a tracker's live target
    # (not retained: under MQTT 3.1.1 the broker clears the flag of a live message) at 4 s
    clock.now = began + 4.0
    client._intercepted("t/rot1/target", b"120", False)
    clock.now = began + LOOK_TIMEOUT_S
    _delay, fn, args = timers.armed[-1]
    fn(*args)
    assert client._look_lost  # nothing the broker held came for LOOK_TIMEOUT_S: timed out
