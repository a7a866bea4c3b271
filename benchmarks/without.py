"""exchange_cpu's ``--without PART[,PART]``: this tree run beside itself with one part of a
turning rotor's reading taken out, in the same rounds, taking turns: the part's cost per exchange
is this tree's CPU less the CPU without it (a difference of two medians on a shared machine,
so a part of a few microseconds is inside the noise). Never for a user: the bridge it starts
publishes less than it must.

Parts (each installed in the bridge's process by without_site/sitecustomize.py, BENCH_WITHOUT):
- ``paho``: paho's ``publish`` of every ``R/bearing`` and ``R/status`` message does nothing
  (it hands back a message info that says sent); the bridge's own work for them (the payloads,
  the comparison with the last, the client's lock and retained copy) is still done.
- ``publishing``: the MQTT service's ``publish_status`` does nothing for a status that is
  ``moving`` after one that was (the first of a turn is published: the benchmark waits for it).
"""

from __future__ import annotations

import subprocess
from pathlib import Path
from typing import Any

from benchmarks.harness import REPO, Scope
from tests.support import bridge_env
from tests.support.process import Spawn

SITE = REPO / "benchmarks" / "without_site"

PARTS = {
    "paho": "paho's publish of R/bearing and R/status",
    "publishing": "publishing a turning rotor's statuses",
}


def spawner(scope: Scope, parts: str) -> Spawn:
    """How a Rig starts this checkout's bridge without ``parts`` (names of PARTS)."""
    env = bridge_env({"BENCH_WITHOUT": parts})
    env["PYTHONPATH"] = f"{SITE}:{env['PYTHONPATH']}"

    def spawn(argv: list[str], log: Path) -> subprocess.Popen[bytes]:
        return scope.spawn(argv, log_name=str(log.relative_to(scope.workdir)), env=env)

    return spawn


def install(parts: str) -> None:
    """In the bridge's process, at start-up (without_site/sitecustomize.py)."""
    for part in parts.split(","):
        if part == "paho":
            _without_paho()
        elif part == "publishing":
            _without_publishing()
        else:
            raise SystemExit(
                f"BENCH_WITHOUT: unknown part {part!r}; choose from {', '.join(PARTS)}"
            )


def _without_paho() -> None:
    import paho.mqtt.client as paho
    from paho.mqtt.enums import MQTTErrorCode

    publish = paho.Client.publish

    def publish_some(self: Any, topic: str, *args: Any, **kwargs: Any) -> Any:
        if topic.endswith(("/bearing", "/status")):
            info = paho.MQTTMessageInfo(0)
            info.rc = MQTTErrorCode.MQTT_ERR_SUCCESS
            return info
        return publish(self, topic, *args, **kwargs)

    paho.Client.publish = publish_some  # type: ignore[method-assign]


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
