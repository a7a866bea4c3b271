"""A nudge (or the other path, ``R/path``) is made from the target the status shows: one judged
while a newer target waits in the mailbox, not yet taken by the lines thread, would be made from
an older one (mailbox.py rule 10a, runtime/rotator.py ``_seen``). The judge and the session are
the real ones on a virtual MD-01 (test_halt_epoch.py's bench); the bench takes the mailbox only
when told, so the order is forced, not timed."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.core.errors import Refused
from bridge.core.model import Nudge, Origin, Source, Stop, Target
from bridge.runtime.rotator import ON_ITS_WAY_MESSAGE
from tests.engine.test_halt_epoch import START_AZ, Bench

WHO = Origin(Source.MQTT)


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[Bench]:
    made = Bench(tmp_path)
    yield made
    made.close()


@pytest.mark.parametrize("stop_first", [False, True])
def test_a_nudge_before_a_target_was_taken_is_refused_and_the_target_goes(
    bench: Bench, stop_first: bool
) -> None:
    """An attack pass: from rest at 30, target 100 then a nudge of +10 before the lines thread
    took the target: the nudge was made from the status (no target: the bearing, 30), replaced
    the 100 in the mailbox, and the rotor went to 40. A review: the same with a STOP put before
    the target (the nudge was made from the bearing, the stop's rule)."""
    if stop_first:
        bench.rot.submit(Stop(Source.MQTT, origin=WHO), "stop")
    bench.rot.submit(Target(100.0, None, Source.MQTT, origin=WHO), "target '100'")
    with pytest.raises(Refused, match="still on its way"):
        bench.rot.submit(Nudge(10.0, None, source=Source.MQTT, origin=WHO), "nudge '+10'")
    bench.v._take()
    bench.v.run_for(30.0)
    assert bench.rot.status.bearing_deg == pytest.approx(100.0, abs=1.0)
    assert [e.message for e in bench.events] == [ON_ITS_WAY_MESSAGE]


def test_a_nudge_once_the_target_is_taken_adds_to_it(bench: Bench) -> None:
    """Taken, the target waiting to go out is in the status (status.py ``pending_wire``, once
    the MD-01's resolution is learned from its replies): a nudge then adds to it."""
    bench.v.run_for(2.0)  # (its replies read: the resolution learned)
    bench.rot.submit(Target(100.0, None, Source.MQTT, origin=WHO), "target '100'")
    bench.v._take()  # the lines thread took it: the status shows it
    assert bench.rot.status.target_az_deg == 100.0 and bench.rot.status.bearing_deg == START_AZ
    bench.rot.submit(Nudge(10.0, None, source=Source.MQTT, origin=WHO), "nudge '+10'")
    bench.v._take()
    bench.v.run_for(30.0)
    assert bench.rot.status.bearing_deg == pytest.approx(110.0, abs=1.0)
    assert not bench.events


def test_a_nudge_after_a_stop_alone_is_made_from_the_bearing(bench: Bench) -> None:
    """The stop's own rule stands: nothing is on its way, the nudge is from where it stands."""
    bench.rot.submit(Stop(Source.MQTT, origin=WHO), "stop")
    bench.rot.submit(Nudge(10.0, None, source=Source.MQTT, origin=WHO), "nudge '+10'")
    bench.v._take()
    bench.v.run_for(30.0)
    assert bench.rot.status.bearing_deg == pytest.approx(START_AZ + 10.0, abs=1.0)


def test_a_nudge_before_the_status_can_show_the_target_is_refused(bench: Bench) -> None:
    """An attack pass: just after a connect the MD-01's resolution is not yet learned, so the
    status cannot show the target taken (its raw value unknown); a nudge then was made from
    the bearing and replaced it: the rotor went to 40."""
    bench.rot.submit(Target(100.0, None, Source.MQTT, origin=WHO), "target '100'")
    bench.v._take()
    assert bench.rot.status.target_az_deg is None  # (taken, not shown yet)
    with pytest.raises(Refused, match="still on its way"):
        bench.rot.submit(Nudge(10.0, None, source=Source.MQTT, origin=WHO), "nudge '+10'")
    bench.v.run_for(30.0)
    assert bench.rot.status.bearing_deg == pytest.approx(100.0, abs=1.0)
    bench.rot.submit(Nudge(10.0, None, source=Source.MQTT, origin=WHO), "nudge '+10'")
    bench.v._take()  # shown now: the nudge is from where it stands
    bench.v.run_for(30.0)
    assert bench.rot.status.bearing_deg == pytest.approx(110.0, abs=1.0)
