"""Attack pass 7 on 7d371f02 (review 25, R25-3): a stamped move read after a lane STOP's copy
waits under the hold for the marker, and "goes only while its expiry lasts" (service.py rule
9, session.py rule 13). The expiry goes with a ``Target`` or a ``Move`` (service.py
``_command``); a target by call sign (``R/target {"call": ...}``) is neither: the service hands
the call to the DX cluster's aimer (``Called``), which makes a ``Toward`` of the spot's place
with no expiry. The remote's call target, sent right after its STOP, its markers lost in a
flood, turns the rotor at the marker 14 s after it was sent with a 5 s expiry, while the same
target sent as a bearing is dropped, said. The service, the aimer, the judge and the session
are the real ones, on a virtual MD-01 (tests/engine/test_halt_epoch.py's bench)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.dxcluster.test_call_overtaken import held_cluster, turned
from tests.engine.test_halt_epoch import START_AZ, Bench
from tests.mqtt.test_review22_lost_lane_copy import markers_back_late
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[Bench]:
    made = Bench(tmp_path)
    yield made
    made.close()


@pytest.mark.parametrize(
    "payload",
    [
        b"230",  # a bearing: dropped at the marker, past its expiry (R25-3's fix)
        b'{"call": "PY1ABC"}',  # Rio, about 230 degrees from Berlin (fixed since c201e676)
    ],
)
def test_a_stamped_target_held_behind_a_lane_stop_does_not_turn_the_rotor_after_its_expiry(
    bench: Bench, payload: bytes
) -> None:
    v = bench.v
    pub = RecordingPublisher()
    svc = MqttService(
        Topics("rotor", {"v": "rotor"}),
        pub,
        wall=lambda: NOW_UNIX + v.now,
        clock=lambda: v.now,  # (the session's clock: the bench's virtual one)
    )
    svc.attach(bench.rot)
    dx, go = held_cluster()
    go.set()
    svc.aim_calls_with(dx.aim)
    pub.take()
    # the remote: S, then its target (stamped, 5 s expiry) right after it
    svc.on_lane_message("rotor/stop", b"", False)  # the lane first: carried out, on hold
    svc.on_message("rotor/stop", b"", False)  # its copy on the main connection
    sent = NOW_UNIX + v.now + 0.002  # (its clock 2 ms ahead: not taken for one before the S)
    svc.on_message("rotor/target", payload, False, stamp=Stamp.of(sent, 5.0))
    if payload.startswith(b"{"):
        turned(dx, 1)()  # (the aimer's look-up)
    v._take()  # noqa: SLF001
    v.run_for(1.0)
    assert bench.sets() == []  # (waits for the marker)
    markers_back_late(svc, pub, v.run_for)  # (lost in a flood; one back 14 s on)
    v._take()  # noqa: SLF001
    v.run_for(40.0)
    assert bench.sets() == [] and abs(v.truth().az_deg - START_AZ) < 4, (
        f"a target stamped with a 5 s expiry turned the rotor 15 s after it was sent: now at "
        f"{v.truth().az_deg:.0f}, sent {bench.sets()}"
    )
    said = [e.message for e in v.errors()]  # (said on R/error: the session's errors)
    assert any("expiry passed while it waited" in m for m in said), said
