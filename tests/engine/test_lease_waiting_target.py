"""A claim of the control lease and a target that waits in the session (session.py rule 23), in
virtual time: the real judge (runtime/rotator.py) on a virtual Rotor-EZ, whose new target
during a turn waits out the brake delay after the stop. What is asserted is what the user
notices: the bearings the controller received, where the rotor rests, the R/error words."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.core.errors import Refused
from bridge.core.model import (
    AuditEvent,
    Claim,
    ErrorEvent,
    FollowQso,
    MotionState,
    Origin,
    Release,
    SetOption,
    Source,
    Target,
    TrackBody,
)
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.sky.catalog import TleCatalog
from tests.engine.test_halt_epoch import BERLIN, START_AZ, between_judge_and_put, served
from tests.engine.test_halt_epoch import Bench as Station
from tests.engine.virtual import WALL_EPOCH_S, VirtualRotator
from tests.support.sky import tle_with_pass

G4XYZ = Origin(Source.MQTT, "G4XYZ")
DL1ABC = Origin(Source.MQTT, "DL1ABC")
HELD = "DL1ABC holds the rotator until"


class Tower:
    """A Rotator (the judge) on a virtual Rotor-EZ idle at 10 degrees; the session takes the
    mailbox when told (``take``), as the lines thread would."""

    def __init__(self, tmp_path: Path, model: str = "rotorez", ahead_s: float = 0.0) -> None:
        emulator: dict[str, object] = {"start_az_deg": 10}
        if model == "rotorez":
            emulator["jitter_deg"] = 0
        self.v = VirtualRotator(model, emulator=emulator)
        self.v.run_until_state(MotionState.IDLE, 30)
        self.audit: list[AuditEvent] = []
        self.events: list[ErrorEvent] = []
        self.rot = Rotator(
            self.v.cfg,
            StateStore(tmp_path / "state.json"),
            lambda s: None,
            self.events.append,
            on_audit=self.audit.append,
            wall=self.v.wall,  # the lease on the bench's clock
            # (``ahead_s``: the station's clock, the wall clock set back that much meanwhile)
            lease_clock=(lambda: self.v.wall() + ahead_s) if ahead_s else None,
        )
        self.v.mailbox.close()  # the judge's mailbox, taken by the bench's session
        self.v.mailbox = self.rot._mailbox
        self.rot._worker.session = self.v.session

    def close(self) -> None:
        self.rot.operators.stop()
        self.v.close()

    def target(self, az: float, who: Origin) -> None:
        self.rot.submit(Target(az, None, Source.MQTT, origin=who), f"target '{az:g}'")
        self.take()

    def claim(self, who: Origin, *, take: bool = True) -> None:
        self.rot.submit(Claim(who.operator, 30, source=Source.MQTT, origin=who), "claim")
        if take:
            self.take()

    def take(self) -> None:
        self.v._take()

    def sets(self, since: float = float("-inf")) -> list[bytes]:
        return [f.data for f in self.v.frames(since=since) if f.data.startswith(b"AP1")]

    def turning_then_waiting(self, who: Origin) -> float:
        """``who`` sends 100, then 300 mid-turn: the stop goes out, 300 waits for the brake.
        The time 300 was sent."""
        self.target(100, who)
        self.v.run_until(lambda v: v.truth().is_moving, 10, "turning to 100")
        self.v.run_for(0.5)
        t = self.v.now
        self.target(300, who)
        self.v.run_until(lambda v: not v.truth().is_moving, 5, "stopped for the new target")
        assert self.sets(since=t) == [] and self.v.truth().in_brake_delay
        assert self.v.status.target_az_deg == 300 and self.v.status.last_operator == who.who
        return t

    def rests(self) -> float:
        """Past the brake delay and a few polls, at rest: the bearing."""
        self.v.run_for(self.v.cfg.motion.brake_delay_s + 3)
        self.v.run_until(lambda v: v.state is MotionState.IDLE, 120, "at rest")
        return self.v.truth().az_deg


@pytest.fixture
def tower(tmp_path: Path) -> Iterator[Tower]:
    made = Tower(tmp_path)
    yield made
    made.close()


def test_a_claim_drops_another_operators_target_waiting_for_the_brake(tower: Tower) -> None:
    """The attack pass: G4XYZ's 300 waited out the brake delay, DL1ABC claimed the lease
    meanwhile, and the rotor then turned to 300 for someone the lease refused."""
    t = tower.turning_then_waiting(G4XYZ)
    tower.claim(DL1ABC)
    bearing = tower.rests()
    assert tower.sets(since=t) == []  # no AP1300: the rotor rests where the stop left it
    assert 10 < bearing < 100
    said = tower.v.errors("refused", since=t)
    assert [(r.command, r.origin) for r in said] == [("target az 300", G4XYZ)]
    assert said[0].message.startswith(f"target dropped before it went out: {HELD}")
    assert said[0].message.endswith("only they may turn it (control lease)")
    assert tower.v.status.target_az_deg is None and tower.v.status.last_error == said[0].message
    # G4XYZ's next word is the judge's to refuse, as any after the claim
    with pytest.raises(Refused, match=HELD):
        tower.target(300, G4XYZ)
    tower.v.run_for(10)
    assert tower.sets(since=t) == []


@pytest.mark.parametrize("claimed", ["after", "before, renewed after"])
def test_the_holders_own_waiting_target_goes_out(tower: Tower, claimed: str) -> None:
    """The claimant's own target, and a renewal by the holder, change nothing."""
    if claimed != "after":
        tower.claim(DL1ABC)
    t = tower.turning_then_waiting(DL1ABC)
    tower.claim(DL1ABC)
    tower.rests()
    assert tower.sets(since=t) == [b"AP1300\r"]
    assert tower.v.truth().az_deg == pytest.approx(300, abs=3.5)
    assert tower.v.errors("refused", since=t) == []


def test_a_turn_under_way_is_no_waiting_target(tower: Tower) -> None:
    """A claim is no stop: G4XYZ's turn already on the wire goes on (DL1ABC may STOP)."""
    tower.target(300, G4XYZ)
    tower.v.run_until(lambda v: v.truth().is_moving, 10, "turning to 300")
    t = tower.v.now
    tower.claim(DL1ABC)
    tower.v.run_until(lambda v: v.state is MotionState.IDLE, 120, "arrived")
    assert tower.v.truth().az_deg == pytest.approx(300, abs=3.5)
    assert tower.sets() == [b"AP1300\r"]
    assert b";" not in [f.data for f in tower.v.frames()]  # no stop
    assert tower.v.errors(since=t) == []


def test_a_target_judged_before_the_claim_and_taken_with_it_is_dropped(tower: Tower) -> None:
    """G4XYZ's target put, DL1ABC's claim before the lines thread took it: one batch."""
    tower.rot.submit(Target(200, None, Source.MQTT, origin=G4XYZ), "target '200'")
    tower.claim(DL1ABC, take=False)
    tower.take()
    tower.rests()
    assert tower.sets() == [] and tower.v.truth().az_deg == pytest.approx(10, abs=1)
    said = tower.v.errors("refused")
    assert [(r.command, r.origin) for r in said] == [("target az 200", G4XYZ)]


def test_a_release_drops_nothing(tower: Tower) -> None:
    """A lease with no holder refuses nobody: G4XYZ's target waiting when it is released
    goes out."""
    t = tower.turning_then_waiting(G4XYZ)
    tower.rot.submit(Release(source=Source.MQTT, origin=DL1ABC), "release")
    tower.take()
    tower.rests()
    assert tower.sets(since=t) == [b"AP1300\r"]
    assert tower.v.errors("refused", since=t) == []


def test_another_operators_azimuth_is_never_taken_into_the_holders_elevation(
    tmp_path: Path,
) -> None:
    """An az/el GS-232B: G4XYZ's bare azimuth 300 put, DL1ABC's claim and then DL1ABC's bare
    elevation 30, all in one batch. The mailbox took G4XYZ's azimuth into DL1ABC's elevation
    (model.combine) and the rotor turned to 300 as the holder's target; a sender's two halves
    combine, another operator's never do."""
    tower = Tower(tmp_path, "gs232b")
    try:
        tower.rot.submit(Target(300, None, Source.MQTT, origin=G4XYZ), "target '300'")
        tower.claim(DL1ABC, take=False)
        tower.rot.submit(Target(None, 30, Source.MQTT, origin=DL1ABC), "target elevation '30'")
        tower.take()
        tower.v.run_until(lambda v: v.truth().el_deg > 29, 60, "elevation turned")
        tower.v.run_until(lambda v: v.state is MotionState.IDLE, 120, "at rest")
        sets = [f.data for f in tower.v.frames() if f.data.startswith(b"W")]
        assert sets == [b"W010 030"]  # the rotor's own azimuth, DL1ABC's elevation
        assert tower.v.truth().az_deg == pytest.approx(10, abs=1)
    finally:
        tower.close()


def test_a_target_judged_before_a_claim_and_put_after_it_never_moves(tower: Tower) -> None:
    """The race between the judge and the mailbox: G4XYZ's target judged allowed, then
    DL1ABC's claim put and taken by the lines thread, then G4XYZ's target put. Before the
    lease's generation was judged at the put, the target came in a batch of its own after the
    claim's, and the rotor turned to 200 for someone the lease refuses."""
    judge = tower.rot._check

    def claimed_meanwhile(command: Target) -> Target:  # (the scripted interleaving)
        judged = judge(command)
        if command.origin == G4XYZ:
            tower.claim(DL1ABC)  # the claim's batch taken before G4XYZ's put
        return judged

    tower.rot._check = claimed_meanwhile  # type: ignore[method-assign]
    with pytest.raises(Refused, match=HELD) as refused:
        tower.target(200, G4XYZ)
    assert refused.value.message.startswith("DL1ABC claimed the control lease while it was judged")
    tower.rests()
    assert tower.sets() == [] and tower.v.truth().az_deg == pytest.approx(10, abs=1)
    said = [e for e in tower.events if e.kind == "refused"]
    assert [(e.command, e.message) for e in said] == [("target '200'", refused.value.message)]
    refusals = [a for a in tower.audit if a.result.startswith("refused")]
    assert [(a.origin, a.command) for a in refusals] == [(G4XYZ, "target '200'")]
    assert tower.v.status.target_az_deg is None


@pytest.mark.parametrize("change", ["DL1ABC's own claim", "a release"])
def test_a_target_judged_before_a_lease_change_that_allows_it_still_goes(
    tower: Tower, change: str
) -> None:
    """The lease changed between the judge and the put, but its sender may still turn it: the
    claimant's own target, anyone's after a release."""
    who = DL1ABC if change.startswith("DL1ABC") else G4XYZ
    if change == "a release":
        tower.claim(G4XYZ)
    judge = tower.rot._check

    def changed_meanwhile(command: Target) -> Target:
        judged = judge(command)
        if change == "a release":
            tower.rot.submit(Release(source=Source.MQTT, origin=DL1ABC), "release")
            tower.take()
        else:
            tower.claim(DL1ABC)
        return judged

    tower.rot._check = changed_meanwhile  # type: ignore[method-assign]
    tower.target(200, who)
    tower.rests()
    assert tower.sets() == [b"AP1200\r"]
    assert tower.v.truth().az_deg == pytest.approx(200, abs=3.5)
    assert [e for e in tower.events if e.kind == "refused"] == []


def _lose_first_bearing(tower: Tower) -> list[bytes]:
    """The first GS-232B bearing (``W...``) written is lost on the line."""
    lost: list[bytes] = []

    def drop(data: bytes, now: float) -> bytes:
        if data.startswith(b"W") and not lost:
            lost.append(data)
            return b""
        return data

    tower.v.to_device = drop
    return lost


@pytest.mark.parametrize("sender", [G4XYZ, DL1ABC], ids=["another's", "the holder's own"])
def test_a_claim_takes_the_try_more_of_another_operators_lost_target(
    tmp_path: Path, sender: Origin
) -> None:
    """A GS-232B takes a bearing at any time: G4XYZ's 200, lost on the line, is sent once more
    when a reading shows the rotor never moved (controller.py rule 11). DL1ABC claimed the
    lease in between, and the try more turned the rotor to 200 for someone the lease refuses.
    It is not sent, said as rule 23's drop, and no stall is called for a turn that never
    began; the holder's own lost target still goes once more."""
    tower = Tower(tmp_path, "gs232b")
    try:
        lost = _lose_first_bearing(tower)
        tower.target(200, sender)
        tower.v.run_until(lambda v: lost, 10, "the first try, lost")
        t = tower.v.now
        tower.v.run_for(0.5)
        tower.claim(DL1ABC)
        tower.v.run_for(30)  # (past the stall timeout from the lost try)
        tower.v.run_until(lambda v: v.state is MotionState.IDLE, 120, "at rest")
        sets = [w.data for w in tower.v.writes if w.t >= t and w.data.startswith(b"W")]
        if sender is DL1ABC:
            assert sets == [b"W200 000\r", b"W200 000\r"]  # the lost one and its try more
            assert tower.v.truth().az_deg == pytest.approx(200, abs=3.5)
            assert tower.v.errors(since=t) == []
            return
        assert sets == [b"W200 000\r"]  # the lost one alone
        assert tower.v.truth().az_deg == pytest.approx(10, abs=1)
        said = tower.v.errors(since=t)
        assert [(r.kind, r.command, r.origin) for r in said] == [
            ("refused", "target az 200", G4XYZ)
        ]
        assert said[0].message.startswith(f"target not sent again: {HELD}")
        assert said[0].message.endswith("only they may turn it (control lease)")
        assert tower.v.status.target_az_deg is None and tower.v.state is MotionState.IDLE
        health = tower.v.status.health
        assert health is not None and health.stalls == 0  # (R/health: no stall counted)
    finally:
        tower.close()


def test_a_claim_drops_another_operators_try_more_waiting(tmp_path: Path) -> None:
    """G4XYZ's 200, lost on a GS-232B's line, waits for its try more (a hold of the stop
    express keeps every target back) when DL1ABC claims the lease: dropped as a waiting
    target is (its first try never moved the rotor), not sent once the hold ends."""
    tower = Tower(tmp_path, "gs232b")
    try:
        lost = _lose_first_bearing(tower)
        tower.target(200, G4XYZ)
        tower.v.run_until(lambda v: lost, 10, "the first try, lost")
        t = tower.v.now
        tower.rot.express_hold(5)
        tower.take()
        tower.v.run_until(lambda v: v.session.targets.again_now, 10, "its try more waiting")
        tower.claim(DL1ABC)
        tower.rot.express_release(5)
        tower.take()
        tower.v.run_for(30)
        sets = [w.data for w in tower.v.writes if w.t >= t and w.data.startswith(b"W")]
        assert sets == [b"W200 000\r"]  # the lost one alone
        assert tower.v.truth().az_deg == pytest.approx(10, abs=1)
        said = tower.v.errors(since=t)
        assert [(r.kind, r.command, r.origin) for r in said] == [
            ("refused", "target az 200 el 0", G4XYZ)
        ]
        assert said[0].message.startswith(f"target not sent again: {HELD}")
        assert tower.v.state is MotionState.IDLE
    finally:
        tower.close()


def test_a_setting_judged_before_a_claim_and_put_after_it_is_refused(tower: Tower) -> None:
    """A controller setting is control too (the lease refuses another operator's): G4XYZ's
    ``jam`` ON judged while the lease was free, DL1ABC's claim put and taken before it was
    put. It went to the Rotor-EZ (``J``) and into the state file under DL1ABC's lease."""
    judge = tower.rot._check

    def claimed_meanwhile(command: SetOption) -> SetOption:
        judged = judge(command)
        tower.claim(DL1ABC)
        return judged  # type: ignore[return-value]

    tower.rot._check = claimed_meanwhile  # type: ignore[method-assign]
    t = tower.v.now
    with pytest.raises(Refused, match=HELD) as refused:
        tower.rot.submit(SetOption("jam", True, Source.MQTT, origin=G4XYZ), "option jam 'ON'")
    assert refused.value.message.startswith("DL1ABC claimed the control lease while it was judged")
    tower.take()
    tower.v.run_for(5)
    assert b"J" not in [f.data for f in tower.v.frames(since=t)]


@pytest.mark.parametrize("start", ["track sun", "follow wsjtx"])
@pytest.mark.parametrize("sender", [G4XYZ, DL1ABC], ids=["another's", "the holder's own"])
def test_a_track_or_follow_start_judged_before_a_claim_and_put_after_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, start: str, sender: Origin
) -> None:
    """G4XYZ's start judged allowed while the lease was free, then DL1ABC's claim put and
    taken by the lines thread, then the start put: tracking (or following) started, and its
    bearings turned the rotor for someone the lease refuses (its moves are the bridge's own,
    never judged again). Refused at its put as a target is; the claimant's own goes on."""
    station = Station(tmp_path)
    try:
        rot = station.rot

        def claimed() -> None:
            rot.submit(Claim("DL1ABC", 30, source=Source.MQTT, origin=DL1ABC), "claim")
            station.v._take()  # (the claim's batch taken before the start's put)

        between_judge_and_put(monkeypatch, rot, claimed)
        command = (
            TrackBody("sun", source=Source.MQTT, origin=sender)
            if start.startswith("track")
            else FollowQso(True, source=Source.MQTT, origin=sender)
        )
        if sender is DL1ABC:
            rot.submit(command, start)
            served(station)
            assert station.sets() != []  # (the holder's: it turns the rotor)
            assert [e for e in station.events if e.kind == "refused"] == []
            return
        refused: Refused | None = None
        try:
            rot.submit(command, start)
        except Refused as exc:
            refused = exc
        served(station)  # (WSJT-X names a partner; the rotor has time to turn)
        assert station.sets() == []
        assert station.v.truth().az_deg == pytest.approx(START_AZ, abs=0.5)
        assert station.v.status.tracking is None and station.v.status.following is None
        assert refused is not None and refused.code == "leased"
        message = refused.message
        assert message.startswith(f"DL1ABC claimed the control lease while it was judged: {HELD}")
        said = [e for e in station.events if e.kind == "refused"]
        assert [(e.command, e.message) for e in said] == [(start, message)]
        refusals = [a for a in station.audit if a.result.startswith("refused")]
        assert [(a.origin, a.command) for a in refusals] == [(G4XYZ, start)]
    finally:
        station.close()


def test_a_claim_released_before_the_try_more_leaves_it_to_go(tmp_path: Path) -> None:
    """G4XYZ's 200, lost on a GS-232B's line, judged while the lease was free; DL1ABC claims
    the lease and releases it again before the reading that sends the try more. The lease is
    free when the try more would go: it goes, as a target judged then would (before: it was
    not sent, and R/error said 'target not sent again: DL1ABC holds the rotator ...' of a
    lease that had ended)."""
    tower = Tower(tmp_path, "gs232b")
    try:
        lost = _lose_first_bearing(tower)
        tower.target(200, G4XYZ)
        tower.v.run_until(lambda v: lost, 10, "the first try, lost")
        t = tower.v.now
        tower.v.run_for(0.5)
        tower.claim(DL1ABC)
        tower.rot.submit(Release(source=Source.MQTT, origin=DL1ABC), "release")
        tower.take()
        tower.v.run_for(30)
        tower.v.run_until(lambda v: v.state is MotionState.IDLE, 120, "at rest")
        sets = [w.data for w in tower.v.writes if w.t >= t and w.data.startswith(b"W")]
        assert sets == [b"W200 000\r", b"W200 000\r"]  # the lost one and its try more
        assert tower.v.truth().az_deg == pytest.approx(200, abs=3.5)
        assert tower.v.errors(since=t) == []
    finally:
        tower.close()


def test_the_drop_counts_the_leases_minutes_on_the_stations_clock(tmp_path: Path) -> None:
    """Rule 23, runtime/operators.py rule 5: the lease is on the station's clock, the wall clock
    never set back. With the wall clock set back 10 minutes, the judge's refusal said
    DL1ABC's 30 minutes left and the drop of G4XYZ's waiting target said 40, the raw wall
    clock's count, for the same lease at the same moment (a cold review)."""
    tower = Tower(tmp_path, ahead_s=600.0)
    try:
        t = tower.turning_then_waiting(G4XYZ)
        tower.claim(DL1ABC)
        with pytest.raises(Refused) as refused:
            tower.target(200, G4XYZ)
        [dropped] = tower.v.errors("refused", since=t)
        assert "(30 min left)" in refused.value.message
        assert "(30 min left)" in dropped.message, dropped.message
    finally:
        tower.close()


@pytest.fixture(scope="module")
def satellite_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A TLE file holding TESTSAT, whose next pass over the bench's station rises within the
    hour (a tracking start sends the rotor to wait where it rises: tracking.py rule 2)."""
    line1, line2, _aos, _los = tle_with_pass(*BERLIN, WALL_EPOCH_S, within_s=3600)
    path = tmp_path_factory.mktemp("tle") / "amateur.tle"
    path.write_text(f"TESTSAT\n{line1}\n{line2}\n")
    return path


@pytest.mark.parametrize(
    "lease", ["DL1ABC's claim", "the sender's own claim", "a claim released again"]
)
def test_a_satellite_looked_up_before_a_claim_and_answered_after_it(
    tmp_path: Path, satellite_file: Path, lease: str
) -> None:
    """G4XYZ's ``track TESTSAT`` judged and taken while the lease was free; the sky worker
    looks the name up in the TLE file, and DL1ABC's claim is taken before its answer. The
    answer started tracking, and the rotor turned to wait for the pass for someone the lease
    refuses (a review: the session judged the lock, the link and the wind at the answer, not
    the lease). Judged against the lease at the answer, as a start put after the claim is: the
    sender's own lease, or one released before the answer, lets it go on."""
    station = Station(tmp_path)
    try:
        rot = station.rot
        rot.catalog = TleCatalog(satellite_file)
        t = station.v.now
        rot.submit(TrackBody("TESTSAT", source=Source.MQTT, origin=G4XYZ), "track 'TESTSAT'")
        station.v._take()  # the look-up asked; its answer comes with the next step
        claimant = G4XYZ if lease.startswith("the sender's") else DL1ABC
        rot.submit(Claim(claimant.operator, 30, source=Source.MQTT, origin=claimant), "claim")
        if lease.endswith("released again"):
            rot.submit(Release(source=Source.MQTT, origin=DL1ABC), "release")
        station.v._take()
        station.v.run_for(60.0)
        if lease != "DL1ABC's claim":
            assert station.sets() != []  # tracking started: the rotor goes to wait for AOS
            assert station.v.status.tracking is not None
            assert [e for e in station.events if e.kind == "refused"] == []
            return
        assert station.sets() == []
        assert station.v.truth().az_deg == pytest.approx(START_AZ, abs=0.5)
        assert station.v.status.tracking is None
        said = station.v.errors("refused", since=t)
        assert [(r.command, r.origin) for r in said] == [("track 'TESTSAT'", G4XYZ)]
        assert said[0].message.startswith(f"tracking not started: {HELD}")
        assert said[0].message.endswith("only they may turn it (control lease)")
        assert station.v.status.last_error == said[0].message
    finally:
        station.close()


@pytest.mark.parametrize("start", ["track sun", "follow wsjtx"])
@pytest.mark.parametrize("sender", [G4XYZ, DL1ABC], ids=["another's", "the holder's own"])
def test_a_track_or_follow_start_judged_before_a_claim_and_taken_with_it(
    tmp_path: Path, start: str, sender: Origin
) -> None:
    """G4XYZ's start put while the lease was free, DL1ABC's claim put before the lines thread
    took it: one batch. Tracking (or following) started after the claim in it, and its
    bearings, the bridge's own, turned the rotor under DL1ABC's lease; a target in that batch
    is dropped (session.py rule 23), and so is a start now. The claimant's own goes on."""
    station = Station(tmp_path)
    try:
        rot = station.rot
        command = (
            TrackBody("sun", source=Source.MQTT, origin=sender)
            if start.startswith("track")
            else FollowQso(True, source=Source.MQTT, origin=sender)
        )
        rot.submit(command, start)
        rot.submit(Claim("DL1ABC", 30, source=Source.MQTT, origin=DL1ABC), "claim")
        served(station)  # (one batch; WSJT-X names a partner; the rotor has time to turn)
        if sender is DL1ABC:
            assert station.sets() != []  # (the holder's: it turns the rotor)
            assert station.v.errors("refused") == []
            return
        assert station.sets() == []
        assert station.v.truth().az_deg == pytest.approx(START_AZ, abs=0.5)
        assert station.v.status.tracking is None and station.v.status.following is None
        said = station.v.errors("refused")
        assert [(r.command, r.origin) for r in said] == [(start, G4XYZ)]
        feature = "tracking" if start.startswith("track") else "following"
        assert said[0].message.startswith(f"{feature} not started: {HELD}")
        assert said[0].message.endswith("only they may turn it (control lease)")
    finally:
        station.close()
