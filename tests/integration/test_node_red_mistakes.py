"""What a Node-RED flow's usual mistakes do, end to end: a real mosquitto, the emulated Rotor-EZ
on a pty and the App in-process (tests/support/rig.py), commands published by an MQTT 5 client
as Node-RED's mqtt out node sends them (docs/node-red.md). A mistake must move nothing and be
said on ``R/error``, never fail silently.

What is asserted is what a user sees: the refusal on ``R/error`` and the controller's frames
(``AP1xxx<CR>`` is the Rotor-EZ's "store and go"). Absence is proven by order: after a command
that must move nothing, one that moves the rotor; its frame is the first since.
"""

from __future__ import annotations

import json
import time

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from tests.support.rig import Rig


def moves(rig: Rig, since: float) -> list[bytes]:
    """The frames that turned the rotor since ``since`` (not the polls)."""
    return [f.data for f in rig.emu.log() if f.time_s >= since and f.data.startswith(b"AP1")]


def refusal(rig: Rig, flow: paho.Client, payload: str, *props: tuple[str, str]) -> str:
    """Publish ``payload`` on R/target with the user properties ``props``, as Node-RED's mqtt
    out node does with ``msg.userProperties``; the refusal's message on R/error."""
    t = time.monotonic()
    properties = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
    properties.UserProperty = list(props)
    flow.publish(rig.t("target"), payload, qos=1, properties=properties).wait_for_publish(5)
    error = json.loads(rig.probe.wait_for(rig.t("error"), after=t).payload)
    assert error["kind"] == "refused"
    return str(error["message"])


def test_a_stamp_a_flow_got_wrong_is_refused_saying_what_is_wrong(rig: Rig) -> None:
    """Node-RED sets MQTT 5 user properties from ``msg.userProperties``. A flow that gives
    ``{"expiry": "5"}`` alone believes its targets are refused when late: without ``sent``
    nothing could tell their age, and they were carried out however late, without a word. One
    that stamps ``sent`` with JavaScript's ``Date.now()`` (milliseconds) was told the
    station's clock went back. Neither moves the rotor."""
    """Node-RED sets MQTT 5 user properties from ``msg.userProperties``: a flow that gives
    ``{"expiry": "5"}`` alone believes its targets are refused when late. Without ``sent``
    nothing could tell their age: they were carried out however late, and not a word."""
    rig.add("tower", emu={"start_az_deg": 10})
    rig.start()
    rig.ready("tower")
    flow = paho.Client(CallbackAPIVersion.VERSION2, client_id="node-red", protocol=paho.MQTTv5)
    flow.connect("127.0.0.1", rig.broker.port)
    flow.loop_start()
    try:
        t = time.monotonic()
        assert "send time cannot be read" in refusal(rig, flow, "250", ("expiry", "5"))
        sent = f"{time.time() * 1000:.0f}"
        message = refusal(rig, flow, "260", ("sent", sent), ("expiry", "5"))
        assert f"sent='{sent}' is in milliseconds: give unix seconds" in message
        flow.publish(rig.t("target"), "120", qos=1).wait_for_publish(5)
        rig.arrived("tower", 120)
        assert moves(rig, t) == [b"AP1120\r"]
    finally:
        flow.loop_stop()
        flow.disconnect()
