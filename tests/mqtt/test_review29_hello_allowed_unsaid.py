"""Cold review 29: lastword.py rule 15 sends a marker again at QoS 1, and a PUBACK 0x87 on the
hello topic denies it (delivery.py rule 11): said on ``B/bridge/info`` and in each rotator's
status (``on_denied``). A later connection's hello coming back allows the topic again
(client.py ``_markers_back``: "a refusal a marker's PUBACK said is over"), but says nothing:
``on_allowed`` is never called, so ``B/bridge/info`` goes on naming the hello topic denied after
the ACL was put right (the fence topic's probe, in the same case, says it: ``_fence_back``).
"""

from __future__ import annotations

from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.client import MqttClient
from bridge.settings import MqttSettings
from tests.support import wait_until

HELLO = "t/bridge/hello"


def test_a_hello_denied_by_a_markers_puback_is_said_allowed_when_a_hello_comes_back() -> None:
    said: list[str] = []
    client = MqttClient(
        MqttSettings(port=1, base_topic="t", client_id="hello-under-test"),
        will_topic="t/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        on_denied=lambda topic, problem: said.append(f"denied {topic}"),
        on_allowed=lambda topic: said.append(f"allowed {topic}"),
        on_markers=lambda readable: None,
        claim=Claim(Instance.me("hello-under-test"), "t", "t/bridge/info", HELLO),
        fence_topic="t/bridge/fence",
    )
    client._delivery.deny(HELLO, "publish to", "Not authorized")  # a resent marker's PUBACK
    wait_until(lambda: said == [f"denied {HELLO}"], 10, "the denial said")
    look = client._look
    assert look is not None
    hello = look.begin()  # the next connection's look: its hello comes back
    client._look_saw(look, HELLO, hello)
    assert not client._delivery.denied(HELLO)  # (allowed again in the client's own list)
    wait_until(lambda: said[-1] == f"allowed {HELLO}", 2, "the hello topic said allowed again")
