"""client.py rule 16: the fence's verdicts are reported on threads of their own; a late one
(an older connection's "allowed") never clears the problem after a newer "denied". Whether the
markers can come back at all is another verdict: the fence denied and the hello not back."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import pytest

import bridge.interfaces.mqtt.client as client_module
from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.client import MqttClient
from bridge.settings import MqttSettings
from tests.support import wait_until

FENCE = "t/bridge/fence"


class HeldThreads:
    """``threading`` as the client sees it, but a thread it starts is held, run by the test."""

    def __init__(self) -> None:
        self.held: list[Callable[[], None]] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(threading, name)

    def Thread(self, target: Callable[..., None], args: tuple[Any, ...] = (), **_: Any) -> Any:  # noqa: N802
        held = self.held

        class Held:
            def start(self) -> None:
                held.append(lambda: target(*args))

        return Held()


def test_an_older_connection_s_allowed_coming_late_leaves_the_markers_denied(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    said: list[str] = []
    client = MqttClient(
        MqttSettings(port=1, base_topic="t", client_id="fence-under-test"),
        will_topic="t/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        on_denied=lambda topic, problem: said.append(f"denied {topic}"),
        on_allowed=lambda topic: said.append(f"allowed {topic}"),
        fence_topic=FENCE,
    )
    denied = f"denied {FENCE}"
    client._delivery.deny(FENCE, "read back what it publishes on", "the probe was lost")
    wait_until(lambda: said == [denied], 10, "the first connection's denial said")
    threads = HeldThreads()
    with monkeypatch.context() as m:
        m.setattr(client_module, "threading", threads)
        client._fence_back(FENCE)  # the next connection's probe came back: its report waits
    assert len(threads.held) == 1
    client._delivery.deny(FENCE, "read back what it publishes on", "the probe was lost")
    wait_until(lambda: said == [denied, denied], 10, "a newer connection's denial said")
    threads.held[0]()  # the older "allowed" comes late
    assert said == [denied, denied]  # the problem stays said
    client._fence_back(FENCE)  # a probe back on a newer connection still: said
    wait_until(lambda: said[-1] == f"allowed {FENCE}", 10, "allowed again")


def looking_client(verdicts: list[bool], said: list[str]) -> MqttClient:
    return MqttClient(
        MqttSettings(port=1, base_topic="t", client_id="markers-under-test"),
        will_topic="t/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        on_denied=lambda topic, problem: said.append(topic),
        on_markers=verdicts.append,
        claim=Claim(Instance.me("markers-under-test"), "t", "t/bridge/info", "t/bridge/hello"),
        fence_topic=FENCE,
    )


@pytest.mark.parametrize("denied_first", [True, False])
def test_the_markers_are_lost_only_when_the_fence_is_denied_and_the_hello_never_came_back(
    denied_first: bool,
) -> None:
    """lastword.py rule 7: each marker comes back on the hello topic too, so a denied fence
    alone turns no marker off (with the fence denied, rotctld's S fenced nothing); the fence
    denied and this connection's hello not back in the look's time does, whichever is known
    first. A hello that comes back says the markers can be read."""
    verdicts: list[bool] = []
    said: list[str] = []
    client = looking_client(verdicts, said)
    look = client._look
    assert look is not None
    n = int(look.begin().split()[-1])
    if denied_first:
        client._delivery.deny(FENCE, "read back what it publishes on", "the probe was lost")
        wait_until(lambda: said == [FENCE], 10, "the denial said")
        assert verdicts == []  # (the hello may still come back)
        client._look_timed_out(n)
    else:
        client._look_timed_out(n)
        assert verdicts == []  # (the fence may work)
        client._delivery.deny(FENCE, "read back what it publishes on", "the probe was lost")
    wait_until(lambda: verdicts == [False], 10, "the markers lost")
    hello = look.begin()  # the next connection's look, its hello back
    client._look_saw(look, "t/bridge/hello", hello)
    assert verdicts == [False, True]


def test_a_hello_back_after_the_look_s_time_says_the_markers_come_back() -> None:
    """The look's time is up (a broker slow to send its retained messages, each before the
    hello), the fence denied: the markers are said lost; this connection's hello, come back
    later, says they come back there after all (before: they stayed off for the connection,
    and rotctld's S fenced nothing)."""
    verdicts: list[bool] = []
    said: list[str] = []
    client = looking_client(verdicts, said)
    look = client._look
    assert look is not None
    hello = look.begin()
    client._hello_out = hello  # (as ``_opened`` keeps it)
    n = int(hello.split()[-1])
    client._delivery.deny(FENCE, "read back what it publishes on", "the probe was lost")
    wait_until(lambda: said == [FENCE], 10, "the denial said")
    client._look_timed_out(n)
    look.end(timed_out=True)  # (as ``_end_look`` does on a live connection)
    assert verdicts == [False]
    assert client._look_saw(look, "t/bridge/hello", hello)  # (its own: no marker)
    assert verdicts == [False, True]


def test_the_look_s_timer_at_the_hello_s_return_leaves_the_markers_readable() -> None:
    """The hello comes back as the look's timer fires (on its own thread, before paho's has
    ended the look): the hello's "readable" is the last word, whatever the order."""
    verdicts: list[bool] = []
    said: list[str] = []
    client = looking_client(verdicts, said)
    look = client._look
    assert look is not None
    hello = look.begin()
    client._hello_out = hello
    n = int(hello.split()[-1])
    client._probe = b"probe " + hello  # (never back: the hello's return denies the fence)
    end_look = client._end_look

    def timer_first(*args: Any, **kw: Any) -> None:
        client._end_look = end_look  # type: ignore[method-assign]
        client._look_timed_out(n)  # the timer, between the hello's verdict and the look's end
        end_look(*args, **kw)

    client._end_look = timer_first  # type: ignore[method-assign]
    client._look_saw(look, "t/bridge/hello", hello)
    wait_until(lambda: said == [FENCE], 10, "the denial said")
    assert verdicts and verdicts[-1] is True, verdicts


def test_the_look_s_timer_at_the_probe_s_return_leaves_the_markers_readable() -> None:
    """A connection after one whose fence was denied (the ACL fixed since): its probe comes
    back as the look's timer fires, before the denial is taken back: the probe's "readable"
    is the last word."""
    verdicts: list[bool] = []
    said: list[str] = []
    client = looking_client(verdicts, said)
    look = client._look
    assert look is not None
    client._delivery.deny(FENCE, "read back what it publishes on", "the probe was lost")
    wait_until(lambda: said == [FENCE], 10, "the older connection's denial said")
    hello = look.begin()
    client._hello_out = hello
    n = int(hello.split()[-1])
    probe = client._probe = b"probe " + hello
    fence_back = client._fence_back

    def timer_first(topic: str) -> None:
        client._look_timed_out(n)  # the timer, between the probe's verdict and the allow
        fence_back(topic)

    client._fence_back = timer_first  # type: ignore[method-assign]
    assert client._intercepted(FENCE, probe)
    assert verdicts and verdicts[-1] is True, verdicts


def test_a_hello_back_after_the_look_s_time_before_its_probe_says_the_fence_denied() -> None:
    """MQTT 3.1.1 (no PUBACK says a publish was refused): only the hello coming back before
    the probe tells the broker drops the fence topic; a hello that came back after the look's
    time was read past, and B/bridge/info never named the fence topic for that connection."""
    verdicts: list[bool] = []
    said: list[str] = []
    client = looking_client(verdicts, said)
    look = client._look
    assert look is not None
    hello = look.begin()
    client._hello_out = hello
    client._probe = b"probe " + hello  # (never back)
    client._look_timed_out(int(hello.split()[-1]))
    look.end(timed_out=True)  # (as ``_end_look`` does on a live connection)
    assert verdicts == [] and said == []  # (nothing known yet)
    assert client._look_saw(look, "t/bridge/hello", hello)
    wait_until(lambda: said == [FENCE], 10, "the fence's denial said")
    assert verdicts == [True]  # (the markers come back on the hello topic)
