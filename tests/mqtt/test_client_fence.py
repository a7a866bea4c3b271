"""client.py rule 16: the fence's verdicts are reported on threads of their own; a late one
(an older connection's "allowed") never turns the markers on after a newer "denied"."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import pytest

import bridge.interfaces.mqtt.client as client_module
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
    assert said == [denied, denied]  # the markers stay off
    client._fence_back(FENCE)  # a probe back on a newer connection still: said
    wait_until(lambda: said[-1] == f"allowed {FENCE}", 10, "allowed again")
