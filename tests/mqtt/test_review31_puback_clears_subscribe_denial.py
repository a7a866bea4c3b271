"""Review 31 on 51f4ba95 (delivery.py rule 11): a PUBACK that took a QoS 1 message on a
denied topic allows the topic again, whatever the denial was. The fence topic's denial may
be its SUBSCRIBE's (SUBACK 0x87, client.py ``_denied``) or its probe not read back
(``_judge_probe``): a broker that lets the bridge publish on B/bridge/fence but not read it
takes every resent marker there (PUBACK success), and the denial of *reading* it is cleared
and said over on B/bridge/info, although no marker can come back on it.

What it costs: the markers come back on the hello topic alone (lastword.py rule 7). An ACL
reload then denies the hello topic; the resent markers' PUBACKs say 0x87 on the hello and
success on the fence, so both topics are never refused together (rule 15, ``markers_refused``),
the markers are never known denied, and a lane STOP's hold, its copy counted, waits for a
marker that cannot come for as long as the connection lives: every target after the STOP
waits with it (before 51f4ba95 the SUBSCRIBE denial stayed, both were refused, and the count
copy ended the hold, rule 13).
"""

from __future__ import annotations

import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

import bridge.interfaces.mqtt.client as client_module
import bridge.interfaces.mqtt.delivery as delivery_module
from tests.mqtt.test_attack5_refused_markers import ConfirmedRig, _delivery
from tests.mqtt.test_client_fence import FENCE, HeldThreads, looking_client


def test_a_puback_on_the_fence_topic_does_not_clear_its_subscribe_denial() -> None:
    delivery, paho_client = _delivery()
    fence = "rotor/bridge/fence"
    delivery.deny(fence, "subscribe to", "Not authorized")  # its SUBACK (client.py _denied)
    delivery.send(fence, b"marker", 1, retain=False)  # a resent marker (rule 15)
    for mid, _topic, _data in paho_client.sent:
        delivery.on_publish(None, None, mid, ReasonCode(PacketTypes.PUBACK, "Success"), None)  # type: ignore[arg-type]
    assert delivery.denied(fence), (
        "a PUBACK that took a marker published on B/bridge/fence cleared the broker's refusal "
        "of the bridge's SUBSCRIBE to it (and said it allowed): publishing proves nothing of "
        "reading"
    )


def test_a_hold_ends_when_the_markers_can_come_back_nowhere() -> None:
    rig = ConfirmedRig()
    svc, delivery = rig.svc, rig.delivery
    # at connect: the broker refused the SUBSCRIBE to B/bridge/fence; the hello came back, so
    # the markers come back on the hello topic (lastword.py rule 7)
    delivery.deny("rotor/bridge/fence", "subscribe to", "Not authorized")
    # an ACL reload (SIGHUP) then denies B/bridge/hello too, under the live connection
    svc.on_lane_message("rotor/stop", b"", False)  # a STOP on the lane: carried out, holds
    svc.on_message("rotor/stop", b"", False)  # its copy on the main one, counted
    rig.run(  # ten minutes of a live connection: markers sent again at QoS 1
        600, lambda topic: "Not authorized" if topic == "rotor/bridge/hello" else "Success"
    )
    assert not svc._halts.word.holding, (  # noqa: SLF001
        "neither marker topic can be read back (the fence's SUBSCRIBE denied, the hello's "
        "publish refused 0x87), yet the markers are still taken for readable and the lane "
        "STOP's hold, its copy counted, waits for a marker that cannot come: the fence "
        "topic's PUBACK success cleared its SUBSCRIBE denial"
    )


def test_the_probe_s_puback_at_connect_leaves_the_fence_s_suback_denial(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """client.py rule 16 at connect: the fence topic's SUBSCRIBE refused (SUBACK), then the
    probe published on it at QoS 1 acknowledged (MQTT 3.1.1 PUBACKs carry no reason: every
    one is a success; MQTT 5 says success for a write-only ACL), the hello never back (an
    ACL without B/bridge/#): the look's time up, the markers must be said lost (lastword.py
    rule 7, ``markers_denied``), or a lane STOP's hold waits for a marker for the connection's
    life (rule 14's review 22 F3)."""
    verdicts: list[bool] = []
    said: list[str] = []
    client = looking_client(verdicts, said)
    threads = HeldThreads()
    monkeypatch.setattr(client_module, "threading", threads)
    monkeypatch.setattr(delivery_module, "threading", threads)
    look = client._look  # noqa: SLF001
    assert look is not None
    n = int(look.begin().split()[-1])
    delivery = client._delivery  # noqa: SLF001
    delivery.deny(FENCE, "subscribe to", "Unspecified error")  # the SUBACK (client._denied)
    delivery._pub_topics[7] = FENCE  # noqa: SLF001 (the probe, sent at QoS 1: delivery.send)
    delivery.on_publish(None, None, 7, ReasonCode(PacketTypes.PUBACK, "Success"), None)  # type: ignore[arg-type]
    client._look_timed_out(n)  # noqa: SLF001 (the hello never came back)
    while threads.held:
        threads.held.pop(0)()
    assert verdicts and not any(verdicts), (
        "the fence topic's SUBSCRIBE refused and the hello never back, the markers were not "
        f"said lost: the probe's PUBACK cleared the SUBACK's denial (said {said})"
    )
