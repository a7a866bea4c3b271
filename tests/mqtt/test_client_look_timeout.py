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


class LookRig:
    """A client whose first look has begun, its clock and its timers the test's: ``fire`` runs
    the timer armed last."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch, subscriptions: list[str]) -> None:
        self.clock, self.timers = Clock(), Timers()
        monkeypatch.setattr(client_module, "time", self.clock)
        monkeypatch.setattr(client_module, "threading", self.timers)
        self.client = MqttClient(
            MqttSettings(port=1, base_topic="t", client_id="look-under-test"),
            will_topic="t/bridge/state",
            subscriptions=subscriptions,
            on_message=lambda *a: None,
            claim=Claim(Instance.me("look-under-test"), "t", "t/bridge/info", "t/bridge/hello"),
        )
        look = self.client._look  # noqa: SLF001
        assert look is not None
        self.look = look
        self.begin()

    def begin(self) -> None:
        """The look begins (as a connect does), its timer armed."""
        self.n = int(self.look.begin().split()[-1])
        self.began = self.clock.now
        self.client._look_heard, self.client._look_lost = 0.0, False  # noqa: SLF001
        self.client._arm_look(self.n, self.began, LOOK_TIMEOUT_S)  # noqa: SLF001

    def fire(self) -> None:
        _delay, fn, args = self.timers.armed[-1]
        fn(*args)


def test_a_look_times_out_on_the_broker_s_silence_not_while_it_hands_over_what_it_held(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rig = LookRig(monkeypatch, [])
    client, clock, timers = rig.client, rig.clock, rig.timers
    began = rig.began
    # the retained backlog still coming 4.9 s in: the timer, due at 5 s, looks again
    clock.now = began + 4.9
    client._intercepted("t/junk1/availability", b"online", True)
    clock.now = began + LOOK_TIMEOUT_S
    rig.fire()
    assert not client._look_lost
    assert timers.armed[-1][0] == pytest.approx(4.9)  # 5 s after the last message
    # then silence for LOOK_TIMEOUT_S (an ACL that denies the hello): timed out
    clock.now = began + 4.9 + LOOK_TIMEOUT_S
    rig.fire()
    assert client._look_lost  # (not connected here: nothing more to end)

    # a flood that never ends: LOOK_MAX_S at most
    rig.begin()
    began = rig.began
    while not client._look_lost:
        assert clock.now - began <= LOOK_MAX_S
        clock.now = began + min(LOOK_MAX_S, clock.now - began + LOOK_TIMEOUT_S)
        client._intercepted("t/junk2/availability", b"online", True)  # just before it looks
        rig.fire()
    assert clock.now - began == pytest.approx(LOOK_MAX_S) and client._look_lost


def test_a_retained_command_counts_as_the_broker_s_replay_until_the_look_s_subscribe_is_answered(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Review 33: under MQTT 5 a command topic, subscribed with retain-as-published, hands a
    live command published retained on with the flag set, as the broker's replay of what it
    held (a backlog planted on a filter the bridge reads, stale.py's ``B/+/availability``,
    comes there too). The broker sends a subscription's retained messages as it answers it,
    before it answers the next one: until the SUBACK of the look's SUBSCRIBE, the connect's
    last, they are its replay and keep the look open; after it they say nothing of that."""
    rig = LookRig(monkeypatch, ["t/+/availability"])
    client, clock, began = rig.client, rig.clock, rig.began
    client._look_sub = 7  # the look's SUBSCRIBE, as a connect sends it (``_opened``)
    clock.now = began + 4.9
    client._intercepted("t/junk1/availability", b"online", True)  # the replay, read slowly
    clock.now = began + LOOK_TIMEOUT_S
    rig.fire()
    assert not client._look_lost
    client._on_subscribe(client._client, None, 7, [], None)  # its SUBACK: the replay is over
    clock.now = began + 9.0
    client._intercepted("t/junk2/availability", b"online", True)  # published live, retained
    clock.now = began + 4.9 + LOOK_TIMEOUT_S
    rig.fire()
    assert client._look_lost
