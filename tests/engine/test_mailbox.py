from __future__ import annotations

import select

import pytest

from bridge.core.model import Control, FeatureCommand, Origin, SetOption, Source, Stop, Target
from bridge.session.follow import Follow
from bridge.session.mailbox import LeaseChanged, Mailbox
from bridge.session.tracking import Track
from bridge.sky import Body
from tests.support.waiting import slow


def test_newest_target_replaces_older_ones() -> None:
    mb = Mailbox()
    for az in range(100):
        mb.put(Target(float(az)))
    batch = mb.take()
    assert batch.target == Target(99.0) and batch.stop is None
    assert not mb.take()


def test_stop_drops_targets_that_came_before_it() -> None:
    mb = Mailbox()
    mb.put(Target(10.0))
    mb.put(Stop())
    batch = mb.take()
    assert batch.stop == Stop() and batch.target is None


def test_target_after_stop_is_kept_and_applied_after_the_stop() -> None:
    mb = Mailbox()
    mb.put(Stop())
    mb.put(Target(40.0))
    batch = mb.take()
    assert batch.stop == Stop() and batch.target == Target(40.0)


def test_lock_drops_pending_target_and_latest_option_wins() -> None:
    mb = Mailbox()
    mb.put(Target(10.0))
    mb.put(SetOption("jam", True))
    mb.put(SetOption("endpoint", False))
    mb.put(SetOption("jam", False))
    mb.put_lock(True)
    batch = mb.take()
    assert batch.target is None and batch.lock is True
    assert batch.options == [SetOption("endpoint", False), SetOption("jam", False)]


def test_put_wakes_a_selecting_worker_and_take_clears_the_wakeup() -> None:
    mb = Mailbox()
    assert select.select([mb], [], [], 0)[0] == []
    mb.put(Target(1.0))
    assert select.select([mb], [], [], slow(1))[0] == [mb]
    mb.take()
    assert select.select([mb], [], [], 0)[0] == []


class _PutOnRelease:
    """The mailbox's lock, which lets one ``put`` in the moment ``take`` releases it: the
    critical point where a command can land between taking the batch and draining the pipe."""

    def __init__(self, mb: Mailbox, command: Stop) -> None:
        self._lock = mb._lock
        self._mb = mb
        self._command: Stop | None = command

    def __enter__(self) -> None:
        self._lock.acquire()

    def __exit__(self, *exc: object) -> None:
        self._lock.release()
        command, self._command = self._command, None
        if command is not None:
            self._mb.put(command)


def test_a_stop_put_while_take_runs_still_wakes_the_worker() -> None:
    mb = Mailbox()
    mb.put(Target(10.0))
    mb._lock = _PutOnRelease(mb, Stop())  # type: ignore[assignment]
    first = mb.take()
    assert first.target == Target(10.0) and first.stop is None  # the stop came just after
    # the worker selects again: the stop must wake it at once, not after a poll's timeout
    assert select.select([mb], [], [], 0)[0] == [mb]
    assert mb.take().stop == Stop()


def test_an_axis_left_out_is_kept_from_the_target_it_replaces() -> None:
    """An azimuth then an elevation alone (Hamlib 4.6's PstRotator client sends P 200 30 as two
    datagrams; an MQTT user a bare azimuth and then R/target/elevation) is one target: the
    elevation replaced the azimuth, and the rotor kept its old bearing (4 runs in 12)."""
    box = Mailbox()
    try:
        box.put(Target(200.0, None))
        box.put(Target(None, 30.0))
        assert box.take().target == Target(200.0, 30.0)
        box.put(Target(None, 30.0))
        box.put(Target(210.0, None))
        assert box.take().target == Target(210.0, 30.0)
        box.put(Target(200.0, 10.0))
        box.put(Target(220.0, 40.0))  # both named: the newer wins whole
        assert box.take().target == Target(220.0, 40.0)
        box.put(Target(200.0, None))
        box.put(Stop())
        box.put(Target(None, 30.0))  # after a stop nothing older is left to combine with
        assert box.take().target == Target(None, 30.0)
    finally:
        box.close()


def test_a_flood_of_puts_costs_one_wake_byte_per_batch() -> None:
    """Rule 5: 10,000 targets a second wrote 10,000 bytes and woke the lines thread as often."""
    import os

    box = Mailbox()
    for i in range(1000):
        box.put(Target(float(i % 360)))
    assert os.read(box.fileno(), 4096) == b"\0"  # one byte, not a thousand
    assert box.take().target == Target(999 % 360)
    box.put(Stop())
    ready, _, _ = select.select([box.fileno()], [], [], 0)
    assert ready  # owed again after the take: the stop wakes the worker
    box.close()


def test_every_kind_of_put_wakes_the_worker() -> None:
    """A put that leaves no wake byte waits for the next serial byte or poll: each kind of
    input, however harmless, must wake the lines thread (rule 4)."""
    from bridge.core.model import Control, FeatureCommand
    from bridge.session.follow import Follow, Heard
    from bridge.session.tracking import Track

    puts = {
        "put": lambda mb: mb.put(Target(10.0)),
        "put_lock": lambda mb: mb.put_lock(True),
        "put_lock_saved": lambda mb: mb.put_lock_saved(True),
        "put_lock_unknown": lambda mb: mb.put_lock_unknown(True),
        "put_release": lambda mb: mb.put_release(1),
        "put_express_release": lambda mb: mb.put_express_release(1),
        "put_track": lambda mb: mb.put_track(Track(None)),
        "put_note": lambda mb: mb.put_note("x"),
        "put_health_reset": lambda mb: mb.put_health_reset(),
        "put_ending": lambda mb: mb.put_ending(),
        "put_control": lambda mb: mb.put_control(Control("DL1ABC", 0.0)),
        "put_follow": lambda mb: mb.put_follow(Follow(True)),
        "put_heard": lambda mb: mb.put_heard(Heard("JA1ABC", "PM95", False)),
        "put_wind": lambda mb: mb.put_wind(80.0),
        "put_feature": lambda mb: mb.put_feature(FeatureCommand(feature="x", name="y")),
    }
    named = {n for n in dir(Mailbox) if n == "put" or n.startswith("put_")}
    # the express's hold goes in just before its stop, whose put wakes the worker
    assert named - {"put_express_hold"} == set(puts), "a new kind of put: add it here"
    for name, put in puts.items():
        mb = Mailbox()
        try:
            put(mb)
            assert select.select([mb], [], [], 0)[0] == [mb], f"{name} woke nothing"
            # ... and leaves a batch the worker applies (one it takes for empty is dropped:
            # the lock's save, said to the session, was never shown)
            assert mb.take(), f"{name} left a batch that reads as empty"
        finally:
            mb.close()


def test_a_motion_judged_before_a_stop_or_lock_on_put_since_is_dropped() -> None:
    """Rule 10: a stop or lock ON put adds one to the halt count; a target, track or follow
    start put with an older count was judged before it and is dropped; nothing else is."""
    from bridge.session.follow import Follow
    from bridge.session.tracking import Track
    from bridge.sky import Body

    box = Mailbox()
    try:
        judged = box.epoch
        box.put(Stop())
        assert not box.put(Target(10.0), epoch=judged)
        assert not box.put_track(Track(Body.sun()), epoch=judged)
        assert not box.put_follow(Follow(True), epoch=judged)
        batch = box.take()
        assert batch.stop == Stop() and (batch.target, batch.track, batch.follow) == (None,) * 3
        judged = box.epoch
        box.put_lock(True)
        box.put_lock(False)  # the OFF in the same batch lets no older target through
        assert not box.put(Target(10.0), epoch=judged)
        batch = box.take()
        assert batch.lock_on and batch.lock is False and batch.target is None
        judged = box.epoch
        box.put_lock(False)  # not a halt: nor are options, releases, OFFs, notes
        box.put(SetOption("jam", True))
        box.put_release(1, clear=True)
        box.put_track(Track(None))
        box.put_follow(Follow(False))
        box.put_note("x")
        assert box.epoch == judged
        assert box.put(Target(20.0), epoch=judged)  # judged after every halt: kept
        assert box.put_track(Track(Body.sun()), epoch=judged)
        assert box.put_follow(Follow(True), epoch=judged)
        box.put(Stop())
        assert box.put(Target(30.0))  # put without a count (the bench's, the session's own)
        assert box.take().target == Target(30.0)
    finally:
        box.close()


def test_a_target_judged_before_another_operators_claim_is_refused_at_its_put() -> None:
    """Rule 14: the generation read before the judge, a claim put since: G4XYZ's target is
    refused naming the lease, and nothing waits; the holder's own, and one judged at the
    claim's generation, are put."""
    mb = Mailbox()
    g4xyz, dl1abc = Origin(Source.MQTT, "G4XYZ"), Origin(Source.MQTT, "dl1abc")
    judged = mb.lease
    held = Control("DL1ABC", 1e9)
    mb.put_control(held)
    with pytest.raises(LeaseChanged) as refused:
        mb.put(Target(200.0, origin=g4xyz), epoch=mb.epoch, lease=judged)
    assert refused.value.control == held and mb.take().target is None
    assert mb.put(Target(200.0, origin=dl1abc), epoch=mb.epoch, lease=judged)
    assert mb.take().target == Target(200.0, origin=dl1abc)
    mb.put_control(None)  # released: anyone's judged before it goes
    assert mb.put(Target(100.0, origin=g4xyz), lease=judged)
    assert mb.take().target == Target(100.0, origin=g4xyz)


def test_a_start_judged_before_another_operators_claim_is_refused_at_its_put() -> None:
    """Rule 14 for a track or follow start and a feature's own command (moving or not): put
    with the generation read before the judge, a claim by DL1ABC put since, G4XYZ's is
    refused and nothing waits; the holder's own goes, and an OFF is never judged."""
    mb = Mailbox()
    g4xyz, dl1abc = Origin(Source.MQTT, "G4XYZ"), Origin(Source.MQTT, "DL1ABC")
    judged = mb.lease
    mb.put_control(Control("DL1ABC", 1e9))
    mb.take()
    puts = {
        "track": lambda who: mb.put_track(Track(Body.sun(), origin=who), lease=judged),
        "follow": lambda who: mb.put_follow(Follow(True, origin=who), lease=judged),
        "aim": lambda who: mb.put_feature(
            FeatureCommand(feature="beam", name="aim", value=1.0, origin=who), lease=judged
        ),
        "label": lambda who: mb.put_feature(
            FeatureCommand(feature="beam", name="label", moves=False, origin=who), lease=judged
        ),
    }
    for name, put in puts.items():
        with pytest.raises(LeaseChanged):
            put(g4xyz)
        assert not mb.take(), name
        assert put(dl1abc), name
        assert mb.take(), name
    assert mb.put_track(Track(None, origin=g4xyz)) and mb.put_follow(Follow(False, origin=g4xyz))
    batch = mb.take()
    assert batch.track == Track(None, origin=g4xyz) and batch.follow == Follow(False, origin=g4xyz)
