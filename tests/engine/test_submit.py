"""One command union, one entry (runtime/rotator.py ``submit``, front.py rule 1): every kind of
command a front end can give reaches the judge through ``submit``, is judged in the house's one
order (docs/architecture.md rule 11: a stop, a lock ON, tracking and following OFF never
refused), and is written to the audit trail there, once; a value outside the union is refused
clearly. The rotator's front half runs on the virtual bench's session (tests/engine/virtual.py),
so what a user would notice is what the emulated controller did.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import pytest

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import (
    COMMANDS,
    AuditEvent,
    Claim,
    Command,
    FeatureCommand,
    FollowQso,
    GoToPreset,
    Lock,
    MotionState,
    Nudge,
    Origin,
    Park,
    Release,
    ResetHealth,
    SentAt,
    SetOption,
    Source,
    Stop,
    TakePath,
    Target,
    Toward,
    TrackBody,
    describe_command,
)
from bridge.runtime.audit import FREE_LINES, QUIET_S, AuditTrail
from tests.engine.test_halt_epoch import START_AZ
from tests.engine.test_halt_epoch import Bench as EpochBench
from tests.support.clock import FakeClock

TOKYO = (35.6875, 139.7917)  # PM95vq
WHO = Origin(Source.MQTT, "DL1ABC")
OTHER = Origin(Source.MQTT, "G4XYZ")


class Bench(EpochBench):
    """The judge every front end calls on a virtual az/el controller, idle at START_AZ, with a
    preset, a park position, a station and WSJT-X (test_halt_epoch.py's bench)."""

    def submit(self, command: Command, described: str) -> None:
        """``command`` through the one entry, then the session takes what it queued (and
        what the state writer said it saved: runtime/kept.py rule 2)."""
        self.rot.submit(command, described)
        self.rot._store.flush()
        self.v._take()

    def refused(self, command: Command, described: str) -> RefusalCode:
        with pytest.raises(Refused) as exc:
            self.rot.submit(command, described)
        self.v._take()
        return exc.value.code

    def rest(self) -> None:
        """Idle with no target waiting (one may wait for a reading: targets.py ``decide``)."""
        self.v.run_until(
            lambda h: h.state is MotionState.IDLE and h.session.targets.pending is None,
            120,
            "the rotor rests",
        )

    def last_audit(self) -> tuple[str, str, str]:
        event = self.audit[-1]
        return event.origin.who, event.command, event.result


@pytest.fixture
def bench(tmp_path: Path) -> Bench:
    return Bench(tmp_path, presets={"EU": 45})


def test_every_kind_of_command_reaches_the_judge_through_submit(bench: Bench) -> None:
    """Each kind does what its front end asked, and the audit trail has it in its sender's
    words and name."""
    status = lambda: bench.v.status  # noqa: E731
    steps: list[tuple[Command, str]] = [
        (Target(120.0, 10.0, origin=WHO), "target 120 10"),
        (GoToPreset("EU", origin=WHO), "preset EU"),
        (Nudge(5.0, None, origin=WHO), "nudge +5"),
        (Park(origin=WHO), "park"),
        (Toward(*TOKYO, "PM95vq", origin=WHO), "target PM95vq"),
        (TakePath(True, origin=WHO), "long path"),
    ]
    seen = []
    for command, described in steps:
        bench.submit(command, described)
        bench.rest()
        seen.append((round(status().bearing_deg or -1), status().parked, status().target_info))
        assert bench.last_audit() == ("DL1ABC", described, "executed")
    assert [(az, parked) for az, parked, _ in seen[:4]] == [
        (120, False),
        (45, False),
        (50, False),
        (180, True),
    ]
    (short_az, _, short), (long_az, _, long) = seen[4:]
    assert short is not None and long is not None
    assert (short.path, long.path, short.locator, long.locator) == (
        "short",
        "long",
        "PM95vq",
        "PM95vq",
    )
    assert short_az == round(short.short_path_deg) and long_az == round(long.long_path_deg)

    bench.submit(TrackBody("sun", origin=WHO), "track sun")
    assert status().tracking is not None and status().tracking.body == "sun"  # type: ignore[union-attr]
    bench.submit(TrackBody("off", origin=WHO), "track off")
    assert status().tracking is None
    bench.submit(FollowQso(True, origin=WHO), "follow wsjtx")
    assert status().following is not None
    bench.submit(FollowQso(False, origin=WHO), "follow off")
    assert status().following is None
    bench.submit(Claim("DL1ABC", 30, origin=WHO), "claim")
    assert status().control is not None and status().control.operator == "DL1ABC"  # type: ignore[union-attr]
    bench.submit(Release(origin=WHO), "release")
    assert status().control is None
    bench.submit(Lock(True, origin=WHO), "lock 'ON'")
    assert status().locked and bench.last_audit() == ("DL1ABC", "lock ON", "executed")
    bench.submit(Lock(False, origin=WHO), "lock 'OFF'")
    assert not status().locked
    bench.submit(Stop(Source.MQTT, WHO), "stop")
    assert bench.last_audit() == ("DL1ABC", "stop", "executed")
    bench.submit(ResetHealth(origin=WHO), "health reset")  # moves nothing, but an attack
    assert bench.last_audit() == ("DL1ABC", "health reset", "executed")  # pass: it ends the
    # baseline and its warnings (a slowing motor), and no record said who did
    # an option this model has not: the judge's own words
    assert bench.refused(SetOption("overlap", True, origin=WHO), "option overlap") == "unsupported"
    assert "has no option 'overlap'" in bench.events[-1].message
    assert bench.last_audit()[2].startswith("refused: ")
    # a feature's own command for no part of this rotator's (test_feature_commands.py has one)
    no_part = FeatureCommand(feature="none", name="go", origin=WHO)
    assert bench.refused(no_part, "none go") == "unsupported"
    assert bench.last_audit() == (
        "DL1ABC",
        "none go",
        "refused: no feature 'none' takes commands on this rotator",
    )
    # every kind of the union was given above
    given = {type(c) for c, _ in steps} | {
        TrackBody,
        FollowQso,
        Claim,
        Release,
        Lock,
        Stop,
        ResetHealth,
        SetOption,
        FeatureCommand,
    }
    assert given == set(COMMANDS)


MOTIONS: list[Command] = [
    Target(200.0, None, origin=OTHER),
    GoToPreset("EU", origin=OTHER),
    Park(origin=OTHER),
    Nudge(10.0, origin=OTHER),
    Toward(*TOKYO, "PM95vq", origin=OTHER),
    TrackBody("sun", None, origin=OTHER),
    FollowQso(True, origin=OTHER),
]
HALTS: list[Command] = [
    Stop(Source.MQTT, OTHER),
    Lock(True, origin=OTHER),
    TrackBody("off", None, origin=OTHER),
    FollowQso(False, origin=OTHER),
]


def test_under_the_lock_every_motion_is_refused_and_every_halt_is_carried_out(
    bench: Bench,
) -> None:
    """The judge's order holds for every kind that moves (the lock first), whichever way the
    motion is named; the halts are never refused."""
    bench.submit(Lock(True, origin=WHO), "lock ON")
    for command in MOTIONS:
        assert bench.refused(command, describe_command(command)) == "locked", command
    for command in HALTS:
        bench.submit(command, describe_command(command))
        assert bench.last_audit()[2] == "executed"
    bench.v.run_for(30)  # long enough for any move the judge let through to show
    truth = bench.v.truth()
    assert truth.az_deg == pytest.approx(START_AZ, abs=0.5) and not truth.is_moving
    assert bench.v.status.bearing_deg == pytest.approx(START_AZ, abs=0.5)  # nothing moved


def test_under_another_operators_lease_every_motion_is_refused_and_every_halt_is_not(
    bench: Bench,
) -> None:
    bench.submit(Claim("DL1ABC", 30, origin=WHO), "claim")
    for command in MOTIONS:
        assert bench.refused(command, describe_command(command)) == "leased", command
        assert "DL1ABC holds the rotator" in bench.events[-1].message
    for command in HALTS:
        bench.submit(command, describe_command(command))
        assert bench.last_audit() == ("G4XYZ", describe_command(command), "executed")
    bench.v.run_for(30)
    truth = bench.v.truth()
    assert truth.az_deg == pytest.approx(START_AZ, abs=0.5) and not truth.is_moving


def test_under_another_operators_lease_a_controller_setting_is_theirs_to_change(
    tmp_path: Path,
) -> None:
    """Changing the controller's settings (a GS-232's speed in the middle of someone's turn)
    is control like a target: another operator's lease refuses it; its holder may."""
    bench = Bench(tmp_path, model="gs232b")
    bench.submit(Claim("DL1ABC", 30, origin=WHO), "claim")
    assert bench.refused(SetOption("speed", "2", origin=OTHER), "option speed 2") == "leased"
    assert "DL1ABC holds the rotator" in bench.events[-1].message
    bench.submit(SetOption("speed", "2", origin=WHO), "option speed 2")
    assert bench.last_audit() == ("DL1ABC", "option speed 2", "executed")


@pytest.mark.parametrize("value", [object(), "target 120", 120.0, None])
def test_a_value_outside_the_union_is_refused_clearly_and_moves_nothing(
    bench: Bench, value: object
) -> None:
    with pytest.raises(Refused) as exc:
        bench.rot.submit(value, "bad")  # type: ignore[arg-type]
    assert exc.value.code is RefusalCode.UNSUPPORTED
    assert f"not a command the bridge knows: {type(value).__name__}" in bench.events[-1].message
    assert bench.events[-1].command == "bad"
    assert not bench.rot._mailbox.take().target


def test_a_nudge_a_preset_and_a_park_are_never_audited_as_the_same_again(bench: Bench) -> None:
    """runtime/audit.py rule 9 folds a sender's same command sent again when it changes
    nothing (an absolute target among them); a nudge, a preset or a park sent again each turn
    the rotor anew (a nudge again turns it further) and are never folded."""
    bench.audit.clear()
    for command, described in [
        (Target(120.0, 10.0, origin=WHO), "target 120 10"),
        (Nudge(5.0, None, origin=WHO), "nudge +5"),
        (GoToPreset("EU", origin=WHO), "preset EU"),
        (Park(origin=WHO), "park"),
        (Stop(Source.MQTT, WHO), "stop"),
    ]:
        bench.submit(command, described)
        bench.rest()
    assert [(e.command, e.same_again) for e in bench.audit] == [
        ("target 120 10", True),
        ("nudge +5", False),
        ("preset EU", False),
        ("park", False),
        ("stop", False),
    ]


def test_a_halt_is_timed_by_its_stamp_when_that_is_earlier_and_never_moves_back(
    bench: Bench,
) -> None:
    """runtime/rotator.py ``halted_s`` (interfaces/mqtt/heartbeat.py rule 8): a STOP or lock ON
    is timed when it came, or by the stamp it carries if that is earlier; a stamp later than
    it came, or one older than the halts before it, moves the time neither ahead nor back."""
    rot = bench.rot
    assert rot.halted_s == -math.inf
    before = time.monotonic()
    bench.submit(Stop(origin=WHO), "stop")
    came = rot.halted_s
    assert before <= came <= time.monotonic() and came == rot.last_halt_s
    bench.submit(Stop(origin=WHO, sent_s=came + 3600), "stop")  # a clock ahead: when it came
    assert came < rot.halted_s <= rot.last_halt_s
    latest = rot.halted_s
    bench.submit(Lock(True, origin=WHO, sent_s=latest - 60), "lock ON")  # before the last
    assert rot.halted_s == latest and rot.last_halt_s > latest
    bench.submit(Lock(False, origin=WHO), "lock OFF")
    now = time.monotonic()
    bench.submit(Stop(origin=WHO, sent_s=now), "stop")  # stamped as it left, came later
    assert rot.halted_s == now


def test_a_halt_keeps_its_stamp_and_of_two_stamped_halts_the_later_stamp_is_the_last(
    bench: Bench,
) -> None:
    """runtime/rotator.py ``halted`` (interfaces/mqtt/service.py rule 9): the last halt's
    stamp is kept with its time; of two stamped halts the later stamp counts, though a
    moment lost putting it on the steady clock made its time a little earlier; an unstamped
    halt later than both ends it (its time, no stamp)."""
    rot = bench.rot
    now = time.monotonic()
    bench.submit(Stop(origin=WHO, sent_s=SentAt(now - 1.0, 1_700_000_000.0)), "stop")
    assert rot.halted == (now - 1.0, 1_700_000_000.0)
    bench.submit(Stop(origin=WHO, sent_s=SentAt(now - 1.0005, 1_700_000_000.001)), "stop")
    assert rot.halted == (now - 1.0, 1_700_000_000.001)
    bench.submit(Stop(origin=WHO, sent_s=SentAt(now - 2.0, 1_699_999_999.0)), "stop")
    assert rot.halted == (now - 1.0, 1_700_000_000.001)  # (an older stamp: not the last)
    bench.submit(Stop(origin=WHO), "stop")  # Home Assistant's: when it came
    assert rot.halted[0] >= now and rot.halted[1] is None


@pytest.mark.xfail(
    strict=True,
    reason="review 28's policy: a halt stamped ahead refuses moves from a right clock for up "
    "to 1 s; the station cannot tell it from a fast-clocked sender's older move; refusing is "
    "the safe side (tests/mqtt/test_review28_halt_ahead.py)",
)
def test_a_halt_stamped_ahead_keeps_no_stamp_later_than_when_it_came(bench: Bench) -> None:
    """Review 26: ``_halted`` puts a halt stamped later than it came at when it came on the
    steady clock (a sender's clock ahead: heartbeat.py rule 8, the test above), but keeps its
    stamp (``SentAt.unix``) as sent, and a move is compared with that stamp alone
    (service.py rule 9). A Node-RED flow whose clock runs 0.8 s fast (inside AHEAD_S, so
    its stamp is read) sends STOP at station time T, stamped T + 0.8; the remote's operator
    sends ``P 200`` at T + 0.5, stamped T + 0.5 (the station's clock, well reckoned): refused
    as sent before the last STOP, though sent after it. Before this change the halt counted
    from when it came, and the move passed. The kept stamp must be no later than the
    station's time when the halt came (as its steady time is)."""
    rot = bench.rot
    now = time.monotonic()
    station_now = 1_700_000_000.0  # (the station's clock when the STOP came)
    bench.submit(Stop(origin=WHO, sent_s=SentAt(now + 0.8, station_now + 0.8)), "stop")
    came_s, stamp = rot.halted
    assert came_s <= time.monotonic()  # (its steady time: when it came, as before)
    assert stamp is not None
    move_stamp = station_now + 0.5  # sent after the STOP came, by a clock that is right
    assert not move_stamp < stamp, (
        "a move sent 0.5 s after a STOP stamped 0.8 s ahead is taken for older: kept stamp "
        f"{stamp - station_now:+.3f} s from when it came"
    )


def test_a_halt_that_changed_nothing_is_audited_so_and_one_that_ended_something_is_not(
    bench: Bench,
) -> None:
    """runtime/audit.py rule 10: a lock ON while the lock was ON, tracking or following OFF with
    nothing to end, changed nothing (folded like a stop, counted on R/audit with the stops); a
    lock ON that locked, an OFF that ended tracking, following or a start on its way to the
    session, each changed something (a line of its own). Each that changed nothing is rule 9's
    ``same_again`` too, and so is a lock OFF."""
    bench.audit.clear()
    steps: list[tuple[Command, str]] = [
        (Lock(True, origin=WHO), "lock ON"),  # locks
        (Lock(True, origin=OTHER), "lock ON"),  # another's, while locked: nothing
        (Lock(False, origin=WHO), "lock OFF"),  # a lock change, never a halt
        (TrackBody("sun", origin=WHO), "track sun"),
        (TrackBody("off", origin=WHO), "track off"),  # ends tracking
        (TrackBody("off", origin=OTHER), "track off"),  # nothing tracked
        (FollowQso(True, origin=WHO), "follow wsjtx"),
        (FollowQso(False, origin=WHO), "follow off"),  # ends following
        (FollowQso(False, origin=OTHER), "follow off"),  # nothing followed
    ]
    for command, described in steps:
        bench.submit(command, described)
    assert [(e.origin.who, e.command, e.unchanged, e.routine) for e in bench.audit] == [
        ("DL1ABC", "lock ON", False, False),
        ("G4XYZ", "lock ON", True, True),
        ("DL1ABC", "lock OFF", False, False),
        ("DL1ABC", "track sun", False, False),
        ("DL1ABC", "track off", False, False),
        ("G4XYZ", "track off", True, True),
        ("DL1ABC", "follow wsjtx", False, False),
        ("DL1ABC", "follow off", False, False),
        ("G4XYZ", "follow off", True, True),
    ]
    # rule 9: a start again may turn the rotor anew; a halt is the same again only when it
    # changed nothing (one that changed something, a storm's park given up, is a line of its
    # own); a lock OFF always
    assert [e.same_again for e in bench.audit] == [
        False,  # lock ON that locked
        True,  # lock ON while ON
        True,  # lock OFF
        False,  # track sun
        False,  # track off that ended it
        True,  # track off with nothing to end
        False,  # follow wsjtx
        False,  # follow off that ended it
        True,  # follow off with nothing to end
    ]
    # a start put and not yet taken by the session: the OFF put behind it ends it
    bench.audit.clear()
    bench.rot.submit(TrackBody("moon", origin=WHO), "track moon")
    bench.submit(TrackBody("off", origin=OTHER), "track off")
    bench.rot.submit(FollowQso(True, origin=WHO), "follow wsjtx")
    bench.submit(FollowQso(False, origin=OTHER), "follow off")
    assert [(e.command, e.unchanged) for e in bench.audit] == [
        ("track moon", False),
        ("track off", False),
        ("follow wsjtx", False),
        ("follow off", False),
    ]
    assert bench.v.status.tracking is None and bench.v.status.following is None


def test_a_lock_on_while_locked_in_a_storm_whose_park_waits_is_a_change(tmp_path: Path) -> None:
    """runtime/audit.py rule 10: a lock ON while the lock is ON changes nothing, but in a storm
    whose park waits for the lock OFF it ends that park (session/wind.py rule 3: not tried again
    in this storm), so it is never audited as a halt that changed nothing; once that park is
    given up, the next one is."""
    bench = Bench(tmp_path, wind_topic="weather/wind", wind_park_above=60)
    bench.submit(Lock(True, origin=WHO), "lock ON")
    bench.rot.wind(90.0)  # a storm under the lock: its park waits for the lock OFF
    bench.v._take()
    bench.v.run_for(2.0)
    wind = bench.v.status.wind
    assert wind is not None and wind.parks and wind.waiting and not wind.halted
    bench.audit.clear()
    bench.submit(Lock(True, origin=OTHER), "lock ON")
    bench.v.run_for(2.0)
    wind = bench.v.status.wind
    assert wind is not None and wind.halted  # the park is given up for this storm
    bench.submit(Lock(True, origin=OTHER), "lock ON")
    assert [e.unchanged for e in bench.audit] == [False, True]
    bench.close()


def _trail_lines(
    tmp_path: Path, events: list[AuditEvent]
) -> tuple[list[dict[str, object]], list[AuditEvent]]:
    """``events`` through the audit trail as the bridge writes them (runtime/audit.py), its
    runs ended: the lines of the file and what R/audit was given."""
    path = tmp_path / "audit.jsonl"
    clock = FakeClock()
    published: list[AuditEvent] = []
    trail = AuditTrail(path, 1_000_000, lambda _r, e: published.append(e), [], clock=clock)
    audited = trail.of("v")
    trail.start()
    try:
        for event in events:
            audited(event)
        clock.t += QUIET_S
        trail.tick()
        trail.flush()
    finally:
        trail.stop()
    return [json.loads(line) for line in path.read_text().splitlines()], published


def test_a_lock_on_sent_again_that_gave_up_a_storm_park_is_a_line_of_its_own(
    tmp_path: Path,
) -> None:
    """runtime/audit.py rules 9 and 10: a lock ON sent again by its sender, nothing carried out
    between, is folded as changing nothing. But a storm that began in between (no audited
    command) owes a park a lock ON gives up for the whole storm (session/wind.py rule 3): that
    lock ON changed something, and its line (and R/audit's) is the only word of who stopped
    the park. A loop republishing lock ON (attack 15's) is exactly such a sender."""
    bench = Bench(tmp_path, wind_topic="weather/wind", wind_park_above=60)
    try:
        bench.submit(Lock(True, origin=WHO), "lock ON")  # locks: a line
        for _ in range(FREE_LINES + 2):  # the loop, while nothing is owed: folded after a few
            bench.submit(Lock(True, origin=WHO), "lock ON")
        bench.rot.wind(90.0)  # a storm under the lock: its park waits for the lock OFF
        bench.v._take()
        bench.v.run_for(2.0)
        wind = bench.v.status.wind
        assert wind is not None and wind.parks and wind.waiting and not wind.halted
        bench.submit(Lock(True, origin=WHO), "lock ON")  # the loop's next: gives the park up
        bench.v.run_for(2.0)
        wind = bench.v.status.wind
        assert wind is not None and wind.halted  # the park is given up for this storm
        ender = bench.audit[-1]
        assert not ender.unchanged  # (the judge says it changed something)
        written, published = _trail_lines(tmp_path, bench.audit)
    finally:
        bench.close()
    assert ender.as_dict() in written, [(d["command"], d.get("count")) for d in written]
    assert ender in published


def test_a_lock_on_right_after_the_storms_first_reading_is_a_line_of_its_own(
    tmp_path: Path,
) -> None:
    """runtime/audit.py rule 10: ``_storm_parks`` reads the status, which has not yet taken a
    wind reading put just before the lock ON; the lock ON put behind it stops that reading's
    park all the same (mailbox.py rule 9: the readings put before it), so the park is given
    up for the storm while the judge calls the lock ON idle, and the trail folds it into the
    sender's run of idle lock ONs. Two senders take turns (neither is rule 9's sent again), so
    only rule 10 folds them."""
    bench = Bench(tmp_path, wind_topic="weather/wind", wind_park_above=60)
    try:
        bench.submit(Lock(True, origin=OTHER), "lock ON")  # locks: a line
        for _ in range(FREE_LINES + 2):  # two loops while nothing is owed: each folded
            bench.submit(Lock(True, origin=WHO), "lock ON")
            bench.submit(Lock(True, origin=OTHER), "lock ON")
        bench.v.run_for(2.0)
        bench.rot.wind(90.0)  # the storm's first reading, not yet taken by the session
        bench.submit(Lock(True, origin=WHO), "lock ON")  # the loop's next, right behind it
        bench.v.run_for(2.0)
        wind = bench.v.status.wind
        assert wind is not None and wind.parks and wind.halted  # the park is given up
        ender = bench.audit[-1]
        written, published = _trail_lines(tmp_path, bench.audit)
    finally:
        bench.close()
    assert ender.as_dict() in written, [(d["command"], d.get("count")) for d in written]
    assert ender in published
