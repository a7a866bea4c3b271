"""exchange_cpu's ``--without PART[,PART]``: this tree run beside itself with one part of a
turning rotor's reading taken out, in the same rounds, taking turns: the part's cost per exchange
is this tree's CPU less the CPU without it (a difference of two medians on a shared machine,
so a part of a few microseconds is inside the noise). Never for a user: the bridge it starts
publishes less than it must. This module is imported by that bridge at start-up
(without_site/sitecustomize.py, BENCH_WITHOUT): it imports nothing of the benchmarks' own.

Parts:
- ``paho``: each status's ``R/bearing`` and ``R/status`` messages (the topics the MQTT service
  names for it) do not reach paho's ``publish`` nor the bridge's own (paho_client.py rule 9):
  they hand back that it was sent.
  The service's own work for them (the payloads, the comparison with the last, the client's
  lock and retained copy) is still done; paho's packet, its queue and the network thread's
  wake-up and write for them are not.
- ``publishing``: the MQTT service's ``publish_status`` does nothing for a status that is
  ``moving`` after one that was (the first of a turn is published: the benchmark waits for
  it): no payload, no paho, no group or listener (Home Assistant's version check) for them.
"""

from __future__ import annotations

import threading
from typing import Any

PARTS = {
    "paho": "paho's publish of R/bearing and R/status",
    "publishing": "publishing a turning rotor's statuses",
}


def unknown(parts: str) -> str | None:
    """Why ``parts`` (comma-separated) cannot be taken out, if one is none of PARTS."""
    bad = [part for part in parts.split(",") if part not in PARTS]
    if not bad:
        return None
    return f"unknown part {', '.join(map(repr, bad))}; choose from {', '.join(PARTS)}"


def install(parts: str) -> None:
    """In the bridge's process, at start-up (without_site/sitecustomize.py)."""
    why = unknown(parts)
    if why is not None:
        raise SystemExit(f"BENCH_WITHOUT: {why}")
    for part in parts.split(","):
        if part == "paho":
            _without_paho()
        else:
            _without_publishing()
    print(f"benchmark: this bridge runs without {parts} (BENCH_WITHOUT)", flush=True)


def _without_paho() -> None:
    import paho.mqtt.client as paho
    from paho.mqtt.enums import MQTTErrorCode

    from bridge.interfaces.mqtt.paho_client import Client
    from bridge.interfaces.mqtt.service import MqttService

    skip = threading.local()  # the topics of the status being published on this thread
    publish_status, publish = MqttService.publish_status, paho.Client.publish
    publish_qos0 = Client.publish_qos0

    def publishing(self: MqttService, rotator_id: str, status: Any) -> None:
        t = self.topics.rotator(rotator_id)
        skip.topics = (t.bearing, t.status)
        try:
            publish_status(self, rotator_id, status)
        finally:
            skip.topics = ()

    def publish_some(self: Any, topic: str, *args: Any, **kwargs: Any) -> Any:
        if topic in getattr(skip, "topics", ()):
            info = paho.MQTTMessageInfo(0)
            info.rc = MQTTErrorCode.MQTT_ERR_SUCCESS
            return info
        return publish(self, topic, *args, **kwargs)

    def publish_some_qos0(self: Client, topic: str, payload: bytes, retain: bool) -> Any:
        if topic in getattr(skip, "topics", ()):
            return MQTTErrorCode.MQTT_ERR_SUCCESS
        return publish_qos0(self, topic, payload, retain)

    MqttService.publish_status = publishing  # type: ignore[method-assign]
    paho.Client.publish = publish_some  # type: ignore[method-assign]
    Client.publish_qos0 = publish_some_qos0  # type: ignore[method-assign]


def _without_publishing() -> None:
    from bridge.core.model import MotionState
    from bridge.interfaces.mqtt.service import MqttService

    publish_status = MqttService.publish_status
    last: dict[str, MotionState] = {}

    def publish_some(self: MqttService, rotator_id: str, status: Any) -> None:
        state, last[rotator_id] = last.get(rotator_id), status.state
        if state is MotionState.MOVING and status.state is MotionState.MOVING:
            return
        publish_status(self, rotator_id, status)

    MqttService.publish_status = publish_some  # type: ignore[method-assign]
