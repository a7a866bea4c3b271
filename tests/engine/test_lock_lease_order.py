"""A lock OFF and the control lease beside motion commands (mailbox.py rule 10a, kept.py rule
2), as a review found them: tests/engine/test_halt_epoch.py's bench, the real judge and
session on a virtual MD-01; the bench takes the mailbox only when told, so the order is
forced, not timed."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.core.errors import Refused
from bridge.core.model import Claim, Lock, MotionState, Nudge, Origin, Source, Target, Toward
from tests.engine.test_halt_epoch import START_AZ, Bench
from tests.support.waiting import slow

ME = Origin(Source.MQTT, "DL1AAA")


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[Bench]:
    made = Bench(tmp_path)
    yield made
    made.close()


@pytest.mark.parametrize("between", ["claim", "lock OFF"])
def test_a_lease_claim_or_lock_off_does_not_hide_a_target_on_its_way_from_a_nudge(
    bench: Bench, between: str
) -> None:
    """mailbox.py rule 10a: a lock OFF takes a place in the order, but is no motion command:
    target 100 still waits untaken, and a nudge then is refused as one made from a status that
    does not show it (when the OFF, or a claim, counted as a halt, the nudge was made from the
    bearing, 30, replaced the 100, and the rotor went to 40)."""
    rot = bench.rot
    rot.submit(Target(100.0, None, Source.MQTT, origin=ME), "target '100'")
    if between == "claim":
        rot.submit(Claim("DL1AAA", 30, source=Source.MQTT, origin=ME), "claim")
    else:
        rot.submit(Lock(False, source=Source.MQTT, origin=ME), "lock OFF")
    with pytest.raises(Refused, match="still on its way"):
        rot.submit(Nudge(10.0, None, source=Source.MQTT, origin=ME), "nudge '+10'")
    bench.v._take()
    bench.v.run_for(30.0)
    assert rot.status.bearing_deg == pytest.approx(100.0, abs=1.0)


def test_a_nudge_is_not_refused_by_the_lease_end_its_own_judge_finds(bench: Bench) -> None:
    """A lease the wall clock has ended (its timer not fired yet) is ended by the nudge's own
    judge: no word against the nudge (when a change of the lease took a place in the order,
    the nudge was dropped as 'a newer command came after it')."""
    rot = bench.rot
    rot.submit(Claim("DL1AAA", 1, source=Source.MQTT, origin=ME), "claim")
    real = rot.operators._wall
    rot.operators._wall = lambda: real() + 120.0  # the lease over by the clock
    rot.submit(Nudge(10.0, None, source=Source.MQTT, origin=ME), "nudge '+10'")
    bench.v._take()
    bench.v.run_for(30.0)
    assert rot.status.bearing_deg == pytest.approx(START_AZ + 10.0, abs=1.0)


def test_a_call_asked_before_its_asker_claims_the_lease_still_turns(bench: Bench) -> None:
    """DL1AAA asks for a call while the lease is free, then claims it before the look-up
    ends: their own claim is no word against their own call."""
    rot = bench.rot
    since, ticket = rot.halts, rot.ticket()
    rot.submit(Claim("DL1AAA", 30, source=Source.MQTT, origin=ME), "claim")
    toward = Toward(35.7, 139.7, "PM95vq", source=Source.DXCLUSTER, origin=ME)
    rot.submit(toward, "call", since=since, ticket=ticket)
    bench.v._take()
    bench.v.run_for(60.0)
    assert bench.sets() != []


def test_the_status_never_says_locked_while_the_rotor_turns(bench: Bench) -> None:
    """kept.py rule 2: a lock OFF is in effect at once and said at once. Said only once
    saved, while its save waited (a slow card, the writer on an earlier save) a target was
    taken and the rotor turned with R/status and R/lock/state saying the lock was ON."""
    rot, store = bench.rot, bench.rot._store
    rot.submit(Lock(True, source=Source.MQTT, origin=ME), "lock ON")
    store.flush()
    bench.v._take()
    bench.v.run_for(2.0)
    assert rot.status.locked
    busy, go = threading.Event(), threading.Event()

    def writer_busy() -> None:
        busy.set()
        go.wait(slow(10))

    store.later(writer_busy)
    assert busy.wait(slow(10))
    try:
        rot.submit(Lock(False, source=Source.MQTT, origin=ME), "lock OFF")
        rot.submit(Target(200.0, None, Source.MQTT, origin=ME), "target '200'")
        bench.v._take()
        bench.v.run_for(3.0)
        shown = rot.status
        assert not (shown.locked and shown.state is MotionState.MOVING), shown
    finally:
        go.set()
        store.flush()
