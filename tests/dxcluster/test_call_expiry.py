"""A stamped call (``R/target {"call": ...}`` with the remote's ``sent`` and ``expiry``): the
MQTT service hands its expiry on the steady clock to the DX cluster's aimer, which makes the
``Toward`` with it (dxcluster/client.py rule 4, interfaces/mqtt/service.py rule 9); one that
waits for the order of a STOP past it turns nothing (session.py rule 13, review 34). The judge
and the session are the real ones, on a virtual MD-01 (tests/engine/test_halt_epoch.py's
bench): what the controller receives is what is asserted."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.core.model import Source, Stop
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.dxcluster.test_call_overtaken import WHO, held_cluster, turned
from tests.engine.test_halt_epoch import Bench
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[Bench]:
    made = Bench(tmp_path)
    yield made
    made.close()


@pytest.mark.parametrize(("back_s", "goes"), [(8.0, False), (2.0, True)])
def test_a_stamped_call_held_past_its_expiry_is_not_turned_to(
    bench: Bench, back_s: float, goes: bool
) -> None:
    """A STOP from the stop lane holds the rotator (its hold 1); the call, read after its copy
    and stamped with a 5 s expiry, is looked up and its target waits for the marker, back
    ``back_s`` later: past the expiry it is dropped, said; within it the rotor turns."""
    v = bench.v
    svc = MqttService(
        Topics("rotor", {"v": "rotor"}),
        RecordingPublisher(),
        wall=lambda: NOW_UNIX + v.now,
        clock=lambda: v.now,
    )
    svc.attach(bench.rot)
    dx, go = held_cluster()
    svc.aim_calls_with(dx.aim)
    t = v.now
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # (the lane's stop: the marker not back yet)
    v._take()
    stamp = Stamp.of(NOW_UNIX + v.now, 5.0)
    svc.on_message("rotor/target", b'{"call": "JA1ABC"}', False, "G4ABC", stamp=stamp)
    go.set()
    turned(dx, 1)()
    v._take()
    v.run_for(back_s)
    assert bench.sets() == []
    v.mailbox.put_release(1)
    v._take()
    v.run_for(40.0)
    said = [e.message for e in v.errors(since=t)]
    assert (bench.sets() != []) is goes, said
    assert any("expiry passed" in m for m in said) is not goes, said
    assert not bench.events, "refused by the judge, not dropped by the session"


def test_an_unstamped_call_has_no_expiry_of_its_own(bench: Bench) -> None:
    """Without a stamp the call waits for the marker however long (lastword.py rule 13)."""
    v = bench.v
    dx, go = held_cluster()
    v.mailbox.put(Stop(Source.MQTT), hold=1)
    v._take()
    dx.aim(bench.rot, "JA1ABC", False, 'target {"call":"JA1ABC"}', WHO)
    go.set()
    turned(dx, 1)()
    v._take()
    v.run_for(30.0)
    v.mailbox.put_release(1)
    v._take()
    v.run_for(40.0)
    assert bench.sets() != []
