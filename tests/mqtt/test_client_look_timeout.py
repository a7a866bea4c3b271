"""client.py rule 14: the first look times out after LOOK_TIMEOUT_S in which nothing came from
the broker, LOOK_MAX_S at most. Under load (load average 20 on two cores), a bridge reading
the 40,000 retained topics planted under its base topic (tests/mqtt/test_attack_sizes.py)
took more than 5 s: "no answer to the bridge's first look in 5 s (does the broker's ACL deny
rotor/bridge/hello?)", judged on part of them, and its own ``offline`` of its last run, read
after the look, was said as another client's. The clock and the timers are the test's here."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import pytest

import bridge.interfaces.mqtt.client as client_module
from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.client import LOOK_MAX_S, LOOK_TIMEOUT_S, MqttClient
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


def test_a_look_times_out_on_the_broker_s_silence_not_while_it_hands_over_what_it_held(
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
    client._arm_look(n, began, LOOK_TIMEOUT_S)

    def fire() -> None:  # the timer armed last, run now
        _delay, fn, args = timers.armed[-1]
        fn(*args)

    # the retained backlog still coming 4.9 s in: the timer, due at 5 s, looks again
    clock.now = began + 4.9
    client._intercepted("t/junk1/availability", b"online", True)
    clock.now = began + LOOK_TIMEOUT_S
    fire()
    assert not client._look_lost
    assert timers.armed[-1][0] == pytest.approx(4.9)  # 5 s after the last message
    # then silence for LOOK_TIMEOUT_S (an ACL that denies the hello): timed out
    clock.now = began + 4.9 + LOOK_TIMEOUT_S
    fire()
    assert client._look_lost  # (not connected here: nothing more to end)

    # a flood that never ends: LOOK_MAX_S at most
    n = int(look.begin().split()[-1])
    began = clock.now
    client._look_heard, client._look_lost = 0.0, False  # (as a connect does)
    client._arm_look(n, began, LOOK_TIMEOUT_S)
    while not client._look_lost:
        assert clock.now - began <= LOOK_MAX_S
        clock.now = began + min(LOOK_MAX_S, clock.now - began + LOOK_TIMEOUT_S)
        client._intercepted("t/junk2/availability", b"online", True)  # just before it looks
        fire()
    assert clock.now - began == pytest.approx(LOOK_MAX_S) and client._look_lost
