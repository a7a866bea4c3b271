"""Review 35 on db50b34f: a new connection's look that finds the markers refused has them
asked again every RESEND_MAX_S "where a PUBACK said so (both topics refused)"
(``Halts.markers_denied``: ``markers_refused((fence, hello))``). But the look's hello goes out
with paho's own publish (client.py ``_opened``), not through delivery.py's ``send``: its
PUBACK 0x87 is matched to no topic, and nothing at the look says the hello topic is refused.
Only the probe's refusal (the fence topic) is known. So the asking starts only where a live
connection had both topics refused before (review 31's rig: the denials kept from the old
connection); a bridge started, or a broker restarted, with a typo in its ACL file denying
B/bridge/# (the review 31 docstring's own case) has its markers off for the connection's life
after the next SIGHUP mends the ACL: rule 11's fences off, rule 13's gap open, and a target
published before rotctld's S and read after it goes to the controller.
"""

from __future__ import annotations

from pathlib import Path

import paho.mqtt.client as paho

from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.client import LOOK_MAX_S, MqttClient
from bridge.interfaces.mqtt.lastword import RESEND_MAX_S
from bridge.settings import MqttSettings
from tests.mqtt.test_attack5_refused_markers import ConfirmedRig
from tests.support import Probe, slow, wait_until
from tests.support.mosquitto import Mosquitto

FENCE, HELLO = "rotor/bridge/fence", "rotor/bridge/hello"
DENIED = f"topic readwrite rotor/#\ntopic deny {FENCE}\ntopic deny {HELLO}\n"
MENDED = "topic readwrite rotor/#\n"


def test_markers_a_first_look_finds_refused_come_back_once_a_sighup_mends_the_acl(
    tmp_path: Path,
) -> None:
    acl = tmp_path / "acl"
    acl.write_text(DENIED)  # a typo denies B/bridge/# to the bridge's user
    # started as root, mosquitto would become user "mosquitto", who cannot read pytest's tmp
    broker = Mosquitto(
        tmp_path / "broker", extra_conf=f"allow_anonymous true\nacl_file {acl}\nuser root"
    )
    broker.start()
    rig = ConfirmedRig()  # a service on a fake clock, the halts timer's work run by hand
    svc, halts = rig.svc, rig.svc._halts  # noqa: SLF001
    client = MqttClient(
        MqttSettings(port=broker.port, base_topic="rotor", client_id="rev35", protocol="5"),
        will_topic="rotor/bridge/state",
        subscriptions=[FENCE, HELLO],
        on_message=lambda topic, payload, retain, *_: svc.on_message(topic, payload, retain),
        on_markers=lambda readable: svc.markers_allowed() if readable else svc.markers_denied(),
        claim=Claim(Instance.me("rev35"), "rotor", "rotor/bridge/info", HELLO),
        fence_topic=FENCE,
    )
    svc.confirm_markers_with(client.publish_marker_confirmed, client.markers_refused)
    probe = Probe(broker.port, FENCE)
    try:
        client.start()
        wait_until(client.connected.is_set, slow(LOOK_MAX_S), "the look's end")
        wait_until(lambda: not halts.word.markers, slow(10), "the markers said lost")
        acl.write_text(MENDED)  # the typo fixed, and a SIGHUP: the connection is kept
        broker.reload()
        wait_until(
            lambda: probe.publish(FENCE, "mended?") and probe.on(FENCE),
            slow(10),
            "the broker lets B/bridge/fence be read again",
        )
        for _ in range(4 * int(RESEND_MAX_S)):  # two minutes of the halts timer's work
            rig.clock.t += 1.0
            halts.resend_if_due()
            sync = client._client.publish("rotor/sync", b"", qos=1)  # noqa: SLF001
            sync.wait_for_publish(slow(5))  # (every PUBACK before it has come)
            assert sync.rc == paho.MQTT_ERR_SUCCESS and sync.is_published()
            halts._refused_now()  # noqa: SLF001
        fenced, calls = rig.fenced_against_rotctlds_stop()
        assert fenced, (
            "two minutes after a SIGHUP let the bridge read and write its markers again, a "
            "target published before rotctld's S and read after it was sent to the controller "
            f"(markers still off: {not halts.word.markers}; the hello topic known refused: "
            f"{client._delivery.denied(HELLO)}): {calls}"  # noqa: SLF001
        )
    finally:
        client.stop()
        probe.close()
        broker.stop()
