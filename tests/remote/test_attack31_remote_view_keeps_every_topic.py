"""Attack 31 (resources under churn): the remote keeps every station topic it ever read.

``rotor-bridge remote`` subscribes to ``B/+/error``, ``B/+/status``, ``B/+/info`` and the like
(every rotator of the station, whatever its id) and puts every message it reads into its
``StationView``, keyed by topic, until the connection drops (run.py rule 4). A neighbour on
the broker (or a station whose rotators' ids changed over the months) that publishes under
many distinct ids grows the remote by a topic and its whole payload each, error events too
(never retained, never read again): an operator's remote left running for days on a shared
broker grows without bound. What the view should hold is bounded by the station's rotators.

Real parts: mosquitto, the bridge on an emulated Rotor-EZ (tests/remote/conftest.py), the
remote in this process with a rotctld endpoint, and a neighbour's MQTT client.
"""

from __future__ import annotations

import pytest

from tests.support.mosquitto import free_port
from tests.support.mqtt import Probe
from tests.support.remote import running_remote
from tests.support.rig import Rig
from tests.support.waiting import wait_until

FEW = 10
MANY = 2000


def _neighbour_publishes(probe: Probe, ids: range, marker: str) -> None:
    """Error events (never retained) under ``rotor/<id>/error`` for every id, then one on the
    station's own ``rotor/error`` (after them, on the same connection: the broker keeps the
    order, so a remote that read it has read them all)."""
    for i in ids:
        probe.publish(f"rotor/n{i}/error", '{"kind":"refused","message":"' + "x" * 200 + '"}')
    probe.publish("rotor/error", marker)


@pytest.mark.xfail(
    strict=True,
    reason="attack 31: the remote keeps every B/<id>/... topic anyone publishes, for as long as "
    "its connection lasts: its memory grows without bound on a shared broker",
)
def test_the_remote_does_not_keep_a_topic_for_every_id_published(
    station: Rig, probe: Probe
) -> None:
    endpoint = {"rotator": "tower", "rotctld_port": free_port()}
    with running_remote(station.broker.port, "DL1ABC", endpoint) as remote:
        _neighbour_publishes(probe, range(FEW), "few")
        wait_until(lambda: remote.view.get("rotor/error") == b"few", 10, "the few read")
        after_few = len(remote.view.topics())

        _neighbour_publishes(probe, range(FEW, FEW + MANY), "many")
        wait_until(lambda: remote.view.get("rotor/error") == b"many", 30, "the many read")
        after_many = len(remote.view.topics())

    assert after_many == after_few, (
        f"the remote's view held {after_few} topics after {FEW} strangers' ids and "
        f"{after_many} after {FEW + MANY}"
    )
