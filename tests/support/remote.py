"""What the remote (bridge/remote/) sent, as the station's broker saw it."""

from __future__ import annotations

import re

from bridge.mosquitto import Mosquitto

_RECEIVED = re.compile(rb"Received PUBLISH from remote-\S+ \(.*'rotor/(\w+)'")


def remote_published(broker: Mosquitto, log_from: int) -> list[bytes]:
    """The leaves of the ``rotor/...`` topics a remote published, in order, since byte
    ``log_from`` of the broker's log (run with ``-v``)."""
    with open(broker.log, "rb") as f:
        f.seek(log_from)
        return _RECEIVED.findall(f.read())
