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

from bridge.remote.rotator import MAX_OTHER_IDS, StationView
from tests.support.clock import FakeClock
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


def test_retained_topics_under_many_ids_are_kept_for_a_bounded_few_and_the_served_always() -> None:
    """remote/rotator.py rule 8, pure: a neighbour's retained descriptions and statuses under
    many ids take at most MAX_OTHER_IDS places; the rotator served keeps every topic of its,
    its newest error event too, whatever came before; a deletion frees a place."""
    view = StationView(FakeClock())
    view.bound_to("rotor")
    view.serve("rotor/tower")
    for i in range(MAX_OTHER_IDS * 10):
        view.put(f"rotor/n{i}/info", b'{"model":"rotorez"}', replayed=True)
        view.put(f"rotor/n{i}/status", b'{"bearing":1}', replayed=True)
        view.put(f"rotor/n{i}/error", b'{"kind":"refused"}')
    view.put("rotor/tower/info", b"tower's", replayed=True)
    view.put("rotor/tower/error", b"tower's event")
    view.put("rotor/bridge/state", b"online", replayed=True)
    view.put("rotor/lock/state", b"ON", replayed=True)  # (the one rotator's: no id "lock")

    kept = view.topics()
    assert len(kept) == 2 * MAX_OTHER_IDS + 4, len(kept)
    assert view.get("rotor/lock/state") == b"ON"
    assert not [t for t in kept if t.startswith("rotor/n") and t.endswith("/error")]
    assert view.get("rotor/tower/info") == b"tower's"
    assert view.get("rotor/tower/error") == b"tower's event"
    assert view.get("rotor/bridge/state") == b"online"

    view.put("rotor/n0/info", b"")  # deleted: n0 still has its status, no place freed
    view.put(f"rotor/n{MAX_OTHER_IDS}/info", b"{}")
    assert view.get(f"rotor/n{MAX_OTHER_IDS}/info") is None
    view.put("rotor/n0/status", b"")  # n0's last topic gone: its place is free
    view.put(f"rotor/n{MAX_OTHER_IDS}/info", b"{}")
    assert view.get(f"rotor/n{MAX_OTHER_IDS}/info") == b"{}"
