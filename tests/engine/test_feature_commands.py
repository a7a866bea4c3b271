"""A feature's own command and status block, declared in its package alone (bridge/feature.py,
session/parts.py rules 5 and 6): a toy feature registered here, and nowhere in core/, runtime/
or session/, has a command parsed from its topic, judged by the one judge like a target (the
lock, the lease, the link; a stop or lock ON wins over it), carried by the mailbox to its part,
whose proposal turns the rotor; what its part shows is in ``R/status``, written by the MQTT
payload code. In virtual time, on the judge every front end calls (test_halt_epoch.py's bench).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import cast

import pytest

import bridge.feature
from bridge.core.errors import Refused
from bridge.core.model import (
    Claim,
    ErrorKind,
    FeatureCommand,
    Lock,
    Origin,
    RotatorStatus,
    Source,
    Stop,
    Target,
    TrackBody,
)
from bridge.feature import CommandTopic, Feature, StatusBlock
from bridge.features import FEATURES
from bridge.interfaces.mqtt import payloads as pl
from bridge.interfaces.mqtt.service import parse_command
from bridge.runtime.rotator import STALE_MESSAGE
from bridge.session.parts import Part, Proposal, Scene, Wake
from bridge.session.session import RotatorSession
from tests.engine.test_halt_epoch import START_AZ, between_judge_and_put
from tests.engine.test_halt_epoch import Bench as EpochBench

WHO = Origin(Source.MQTT, "DL1ABC")
OTHER = Origin(Source.MQTT, "G4XYZ")


class Beam:
    """The toy feature's own state, one per session (parts.py rule 4)."""

    def __init__(self, s: RotatorSession) -> None:
        self.shown: dict[str, object] = {"label": None, "aimed": 0}


def _beam(s: RotatorSession) -> Beam:
    return cast(Beam, s.own["beam"])


def _command(s: RotatorSession, cmd: FeatureCommand, now: float) -> Proposal | None:
    """``aim <az>`` turns the rotor there; ``label <text>`` (no motion) only shows it, and
    ``sneak <az>`` is a command that says it does not move yet proposes a target."""
    beam = _beam(s)
    if cmd.name == "label":
        beam.shown = {**beam.shown, "label": cmd.value}  # a new value when it changes
        return None
    assert isinstance(cmd.value, float)
    beam.shown = {**beam.shown, "aimed": cast(int, beam.shown["aimed"]) + 1}
    target = Target(cmd.value, None, cmd.source, origin=cmd.origin)
    if cmd.name == "raw":  # a part that forgot to judge its target (a bug)
        return Proposal(target=target)
    return Proposal(target=s.cfg.aim.judge(target, s.status.raw_bearing_deg))


BEAM = Part[RotatorSession](
    "beam",
    Wake.STEP,
    True,
    lambda s: False,  # never run by the step: it acts on its commands alone
    lambda s, scene: None,
    lambda s, now: None,
    state=Beam,
    command=_command,
    status=lambda s: _beam(s).shown,
)


def _parse(payload: bytes, by: Origin) -> FeatureCommand:
    word, _, rest = payload.decode().partition(" ")
    if word == "label":
        return FeatureCommand(feature="beam", name="label", value=rest, moves=False, origin=by)
    try:
        az = float(rest)
    except ValueError:
        raise pl.PayloadError(f"not a bearing: {rest!r}") from None
    return FeatureCommand(feature="beam", name=word, value=az, moves=word != "sneak", origin=by)


def _shown(status: RotatorStatus) -> object:
    return status.features.get("beam")


TOY = Feature(
    "beam",
    "docs/architecture.md",
    "turns the rotor on its own command and shows what it did",
    commands=(CommandTopic("beam", "beam", _parse),),
    status=(StatusBlock("beam", _shown, lambda v: v),),
    part=BEAM,
)


class Bench(EpochBench):
    def submit(self, payload: bytes, by: Origin = WHO) -> None:
        """``payload`` on ``R/beam``, parsed as the MQTT service parses it, then judged."""
        command = parse_command("beam", None, payload, by)
        assert isinstance(command, FeatureCommand)
        self.rot.submit(command, f"beam {payload.decode()}")

    def refused(self, payload: bytes, by: Origin = WHO) -> str:
        with pytest.raises(Refused) as exc:
            self.submit(payload, by)
        self.v._take()
        return exc.value.code

    def rest(self) -> None:
        self.v.run_for(40)


@pytest.fixture
def bench(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Bench]:
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, TOY))
    made = Bench(tmp_path)
    assert made.v.cfg.parts is not None and made.v.cfg.parts[-1] is BEAM
    yield made
    made.close()


def test_its_command_over_the_judge_reaches_its_part_and_turns_the_rotor(bench: Bench) -> None:
    bench.submit(b"aim 200")
    bench.v._take()
    bench.rest()
    assert bench.v.truth().az_deg == pytest.approx(200.0, abs=0.5)
    assert bench.v.status.bearing_deg == pytest.approx(200.0, abs=1.0)
    assert bench.v.status.last_operator == "DL1ABC"
    last = bench.audit[-1]
    assert (last.origin.who, last.command, last.result) == ("DL1ABC", "beam aim 200", "executed")


def test_its_status_block_is_in_the_r_status_payload(bench: Bench) -> None:
    bench.submit(b"label Yagi 6el")
    bench.v._take()
    bench.submit(b"aim 90")
    bench.v._take()
    bench.rest()
    doc = json.loads(pl.status_json(bench.v.status, 0.0, has_elevation=True))
    assert doc["beam"] == {"label": "Yagi 6el", "aimed": 1}
    # a status with nothing of it shows no block
    assert "beam" not in json.loads(pl.status_json(RotatorStatus("v"), 0.0, True))


def test_a_stop_put_after_it_in_the_same_batch_wins(bench: Bench) -> None:
    bench.submit(b"aim 200")
    bench.rot.submit(Stop(Source.MQTT, WHO), "stop")
    bench.v._take()  # one batch: the command, then the stop
    bench.rest()
    assert bench.sets() == []
    assert bench.v.truth().az_deg == pytest.approx(START_AZ, abs=0.5)
    assert bench.v.status.features["beam"] == {"label": None, "aimed": 0}  # never reached it


def test_a_lock_on_put_after_it_in_the_same_batch_wins(bench: Bench) -> None:
    bench.submit(b"aim 200")
    bench.rot.submit(Lock(True, origin=WHO), "lock ON")
    bench.rot.submit(Lock(False, origin=WHO), "lock OFF")
    bench.v._take()
    bench.rest()
    assert bench.sets() == []
    assert bench.v.truth().az_deg == pytest.approx(START_AZ, abs=0.5)


def test_put_after_a_stop_in_the_same_batch_it_is_the_later_word(bench: Bench) -> None:
    bench.rot.submit(Stop(Source.MQTT, WHO), "stop")
    bench.submit(b"aim 100")
    bench.v._take()
    bench.rest()
    assert bench.v.truth().az_deg == pytest.approx(100.0, abs=0.5)


def test_a_target_put_before_it_is_replaced_and_one_after_it_wins(bench: Bench) -> None:
    bench.rot.submit(Target(300.0, None, origin=WHO), "target 300")
    bench.submit(b"aim 100")
    bench.v._take()
    bench.rest()
    assert bench.v.truth().az_deg == pytest.approx(100.0, abs=0.5)
    bench.submit(b"aim 200")
    bench.rot.submit(Target(60.0, None, origin=WHO), "target 60")
    bench.v._take()
    bench.rest()
    assert bench.v.truth().az_deg == pytest.approx(60.0, abs=0.5)


def test_the_lock_refuses_its_motion_but_not_what_does_not_move(bench: Bench) -> None:
    bench.rot.submit(Lock(True, origin=WHO), "lock ON")
    assert bench.refused(b"aim 200") == "locked"
    assert bench.events[-1].kind is ErrorKind.REFUSED
    assert bench.audit[-1].result.startswith("refused: rotator is locked")
    bench.submit(b"label tower work")
    bench.v._take()
    bench.rest()
    assert bench.sets() == []
    assert bench.v.status.features["beam"] == {"label": "tower work", "aimed": 0}


def test_the_lease_refuses_it_from_another_operator(bench: Bench) -> None:
    bench.rot.submit(Claim("DL1ABC", 30, origin=WHO), "claim")
    bench.v._take()
    assert bench.refused(b"aim 200", OTHER) == "leased"
    assert "DL1ABC holds the rotator" in bench.events[-1].message
    assert bench.refused(b"label mine", OTHER) == "leased"  # a setting is control too
    bench.submit(b"aim 120")  # its holder's goes
    bench.v._take()
    bench.rest()
    assert bench.v.truth().az_deg == pytest.approx(120.0, abs=0.5)
    assert bench.v.status.features["beam"] == {"label": None, "aimed": 1}


def test_a_command_that_says_it_does_not_move_cannot_turn_the_rotor(bench: Bench) -> None:
    """Judged as no motion (the lock did not refuse it), its part's target is refused."""
    bench.rot.submit(Lock(True, origin=WHO), "lock ON")
    bench.rot.submit(Lock(False, origin=WHO), "lock OFF")
    bench.v._take()
    bench.submit(b"sneak 200")
    bench.v._take()
    bench.rest()
    assert bench.sets() == []
    assert bench.v.errors("refused")[-1].message == "the command does not move the rotor"
    assert bench.v.truth().az_deg == pytest.approx(START_AZ, abs=0.5)


def test_one_judged_before_a_stop_from_another_thread_never_runs_after_it(
    bench: Bench, monkeypatch: pytest.MonkeyPatch
) -> None:
    """mailbox.py rule 10: judged, then a STOP on another thread, then put: dropped, said."""
    between_judge_and_put(
        monkeypatch, bench.rot, lambda: bench.rot.submit(Stop(Source.MQTT, OTHER), "stop")
    )
    with pytest.raises(Refused) as exc:
        bench.submit(b"aim 200")
    bench.v._take()
    bench.rest()
    assert exc.value.code == "stale" and bench.audit[-1].result == f"refused: {STALE_MESSAGE}"
    assert bench.sets() == []


def test_a_feature_no_part_takes_is_refused_clearly(bench: Bench) -> None:
    command = FeatureCommand(feature="nothing", name="go", value=1.0, origin=WHO)
    with pytest.raises(Refused) as exc:
        bench.rot.submit(command, "nothing go 1")
    assert exc.value.code == "unsupported"
    assert bench.events[-1].message == "no feature 'nothing' takes commands on this rotator"
    assert bench.audit[-1].result.startswith("refused: no feature")


def test_a_bad_payload_is_refused_before_the_judge() -> None:
    topic = TOY.commands[0]
    with pytest.raises(pl.PayloadError, match="not a bearing"):
        parse_command("beam", None, b"aim north", WHO, features={"beam": topic})


def test_a_feature_parser_that_breaks_its_contract_is_a_refusal_naming_it() -> None:
    """The toy's parser decodes without a care (as a new feature's might): bytes that are not
    UTF-8 raise UnicodeDecodeError, not PayloadError. That is a refusal on ``R/error`` naming the
    feature and what went wrong, not a traceback in the log and nothing said (a run of the
    suite with 16 workers logged two such tracebacks for ``R/beam``)."""
    topic = TOY.commands[0]
    with pytest.raises(pl.PayloadError, match=r"^beam could not read it \(UnicodeDecodeError: "):
        parse_command("beam", None, b"a\xff 10", WHO, features={"beam": topic})


def test_a_storm_refuses_its_motion_at_the_judge_and_in_the_session(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The judge reads the storm in the status; one put before the judge could know (straight
    in the mailbox, as a command judged just before the storm's reading) the session refuses."""
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, TOY))
    bench = Bench(tmp_path, **STORMY)
    try:
        bench.v.mailbox.put_wind(75.0)
        bench.v._take()
        bench.v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
        assert bench.refused(b"aim 200") == "locked"
        assert bench.events[-1].message == "wind 75 km/h above 60: parked for the storm"
        bench.v.mailbox.put_feature(FeatureCommand(feature="beam", name="aim", value=200.0))
        bench.v._take()
        bench.rest()
        refused = bench.v.errors("refused")[-1]
        assert refused.message == "wind 75 km/h above 60: parked for the storm"
        assert refused.command == "beam aim 200"
        assert bench.v.truth().az_deg == pytest.approx(90.0, abs=0.5)  # still parked
    finally:
        bench.close()


STORMY = {
    "wind_topic": "weather/wind",
    "wind_park_above": 60,
    "wind_release_below": 40,
    "wind_hold_min": 10,
    "wind_park_az_deg": 90,
}


def test_its_motion_ends_tracking_as_a_target_does(bench: Bench) -> None:
    """The later command wins: an aim after a track start leaves the rotor where it aimed, not
    where the sky says at the tracker's next step."""
    bench.rot.submit(TrackBody("sun", origin=WHO), "track sun")
    bench.v._take()
    bench.rest()
    assert bench.v.status.tracking is not None
    bench.submit(b"aim 10")
    bench.v._take()
    bench.rest()
    assert bench.v.status.tracking is None
    assert bench.v.truth().az_deg == pytest.approx(10.0, abs=0.5)


def test_a_track_start_put_after_it_in_the_same_batch_wins(bench: Bench) -> None:
    bench.submit(b"aim 10")
    bench.rot.submit(TrackBody("sun", origin=WHO), "track sun")
    bench.v._take()  # one batch: the aim, then the track start
    bench.rest()
    assert bench.v.status.tracking is not None
    assert bench.v.status.last_command_source == "tracking"


class Sweep:
    """A toy part a command turns on: while on, its step sends the rotor to 300 (parts.py
    rule 7: whatever ends tracking ends it)."""

    def __init__(self, s: RotatorSession) -> None:
        self.on = False
        self.ended: list[str] = []


def _sweep(s: RotatorSession) -> Sweep:
    return cast(Sweep, s.own["sweep"])


def _sweep_command(s: RotatorSession, cmd: FeatureCommand, now: float) -> Proposal | None:
    _sweep(s).on = True
    return None


def _sweep_step(s: RotatorSession, scene: Scene) -> Proposal | None:
    if scene.pending is not None or s.status.bearing_deg == pytest.approx(300.0, abs=1.0):
        return None
    target = Target(300.0, None, Source.MQTT, origin=WHO)
    return Proposal(target=s.cfg.aim.judge(target, s.status.raw_bearing_deg))


def _sweep_end(s: RotatorSession, why: str) -> None:
    _sweep(s).on = False
    _sweep(s).ended.append(why)


SWEEP = Part[RotatorSession](
    "sweep",
    Wake.STEP,
    True,
    lambda s: _sweep(s).on,
    _sweep_step,
    lambda s, now: None,
    state=Sweep,
    command=_sweep_command,
    end=_sweep_end,
)
SWEEP_FEATURE = Feature(
    "sweep",
    "docs/architecture.md",
    "turns the rotor while it is on",
    commands=(
        CommandTopic(
            "sweep", "sweep", lambda p, by: FeatureCommand("sweep", "on", None, origin=by)
        ),
    ),
    part=SWEEP,
)

QUIET_SWEEP = Feature(
    "sweep",
    "docs/architecture.md",
    "turns the rotor while it is on, switched on by a command that says it does not move",
    commands=(
        CommandTopic(
            "sweep",
            "sweep",
            lambda p, by: FeatureCommand("sweep", "on", None, moves=False, origin=by),
        ),
    ),
    part=SWEEP,
)


QUIET_ON = FeatureCommand("sweep", "on", None, moves=False, origin=WHO)


@pytest.fixture
def quiet(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Bench]:
    """A bench whose sweep part is turned on by a command that says it does not move."""
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, QUIET_SWEEP))
    made = Bench(tmp_path)
    yield made
    made.close()


def assert_still(bench: Bench) -> None:
    """No target went out and the rotor stands where it started."""
    assert bench.sets() == []
    assert bench.v.truth().az_deg == pytest.approx(START_AZ, abs=0.5)


@pytest.fixture
def sweeping(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Bench]:
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, SWEEP_FEATURE))
    made = Bench(tmp_path)
    made.rot.submit(FeatureCommand("sweep", "on", None, origin=WHO), "sweep on")
    made.v._take()
    made.v.run_until(lambda h: abs(h.truth().az_deg - START_AZ) > 5, 10, "the sweep turns")
    yield made
    made.close()


def test_a_stop_ends_a_part_its_command_turned_on(sweeping: Bench) -> None:
    sweeping.rot.submit(Stop(Source.MQTT, WHO), "stop")
    sweeping.v._take()
    sweeping.v.run_until(lambda h: not h.status.moving, 10, "stopped")
    stopped = sweeping.v.truth().az_deg
    sent = len(sweeping.sets())
    sweeping.rest()
    assert len(sweeping.sets()) == sent  # no target after the stop
    assert sweeping.v.truth().az_deg == pytest.approx(stopped, abs=0.5)
    assert _sweep(sweeping.v.session).ended[-1] == "stop"


def test_a_lock_ends_a_part_its_command_turned_on(sweeping: Bench) -> None:
    at, sent = sweeping.v.truth().az_deg, len(sweeping.sets())
    sweeping.rot.submit(Lock(True, origin=WHO), "lock ON")
    sweeping.v._take()
    sweeping.rest()
    assert len(sweeping.sets()) == sent  # no target while locked
    assert sweeping.v.truth().az_deg == pytest.approx(at, abs=3.0)  # stopped where it was
    stopped = sweeping.v.truth().az_deg
    sweeping.rot.submit(Lock(False, origin=WHO), "lock OFF")
    sweeping.v._take()
    sweeping.rest()
    assert len(sweeping.sets()) == sent
    assert sweeping.v.truth().az_deg == pytest.approx(stopped, abs=0.5)  # nothing resumed


def test_a_users_target_ends_a_part_its_command_turned_on(sweeping: Bench) -> None:
    sweeping.rot.submit(Target(60.0, None, origin=WHO), "target 60")
    sweeping.v._take()
    sweeping.rest()
    assert sweeping.v.truth().az_deg == pytest.approx(60.0, abs=0.5)


def test_no_parts_step_turns_a_locked_rotor(sweeping: Bench) -> None:
    """Even a part that ignores its end and the scene's lock (a bug) gets no target through."""
    session = sweeping.v.session
    at, sent = sweeping.v.truth().az_deg, len(sweeping.sets())
    sweeping.rot.submit(Lock(True, origin=WHO), "lock ON")
    sweeping.v._take()
    _sweep(session).on = True  # as if its end had been forgotten
    sweeping.rest()
    assert len(sweeping.sets()) == sent
    assert sweeping.v.truth().az_deg == pytest.approx(at, abs=3.0)


def test_a_target_its_part_forgot_to_judge_is_refused_in_a_keep_out_sector(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """pointing.py rule 8: the session checks a part's target against the keep-out sectors
    and the limits, as the judge checks a user's."""
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, TOY))
    bench = Bench(tmp_path, keep_out=[[190, 210]])
    try:
        bench.submit(b"raw 200")
        bench.v._take()
        bench.rest()
        assert bench.sets() == []
        refused = bench.v.errors("refused")[-1]
        assert refused.message == "azimuth 200 is in the keep-out sector 190..210: refused"
        assert refused.command == "beam raw 200"
        assert bench.v.truth().az_deg == pytest.approx(START_AZ, abs=0.5)
    finally:
        bench.close()


def test_a_storm_ends_a_part_its_command_turned_on(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The wind's park is the park: a part turned on before the storm does not take the rotor
    away from it, during the storm or after it."""
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, SWEEP_FEATURE))
    bench = Bench(tmp_path, **STORMY)
    try:
        bench.rot.submit(FeatureCommand("sweep", "on", None, origin=WHO), "sweep on")
        bench.v._take()
        bench.v.run_until(lambda h: abs(h.truth().az_deg - START_AZ) > 5, 10, "the sweep turns")
        bench.v.mailbox.put_wind(75.0)
        bench.v._take()
        bench.v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
        bench.rest()
        assert bench.v.truth().az_deg == pytest.approx(90.0, abs=0.5)  # still parked
        assert _sweep(bench.v.session).on is False
    finally:
        bench.close()


def test_one_put_with_the_storms_reading_reaches_no_part(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Judged just before the storm's reading, in the same batch: refused, never turned on."""
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, SWEEP_FEATURE))
    bench = Bench(tmp_path, **STORMY)
    try:
        bench.v.mailbox.put_feature(FeatureCommand("sweep", "on", None, origin=WHO))
        bench.v.mailbox.put_wind(75.0)
        bench.v._take()
        bench.v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
        bench.rest()
        assert bench.v.truth().az_deg == pytest.approx(90.0, abs=0.5)
        assert _sweep(bench.v.session).on is False
        refused = bench.v.errors("refused")[-1]
        assert refused.message == "wind 75 km/h above 60: parked for the storm"
        assert refused.command == "sweep on"
    finally:
        bench.close()


def test_a_part_turned_on_while_locked_does_not_turn_the_rotor_once_unlocked(quiet: Bench) -> None:
    """parts.py rule 7: a command that says it does not move the rotor is taken while locked;
    if it turned on a part that moves, releasing the lock ends that part: the release is not
    a word to move, and the command came under the lock."""
    bench = quiet
    bench.rot.submit(Lock(True, origin=WHO), "lock ON")
    bench.v._take()
    bench.rot.submit(QUIET_ON, "sweep")
    bench.v._take()
    bench.rest()
    assert _sweep(bench.v.session).on  # taken: it does not move the rotor by itself
    bench.rot.submit(Lock(False, origin=WHO), "lock OFF")
    bench.v._take()
    bench.rest()
    assert_still(bench)
    assert _sweep(bench.v.session).ended[-1] == "lock released"
    bench.rot.submit(QUIET_ON, "sweep")
    bench.v._take()
    bench.v.run_until(lambda h: abs(h.truth().az_deg - START_AZ) > 5, 10, "turned on again")


def test_a_part_turned_on_under_the_lock_with_the_release_in_the_same_batch_stays_still(
    quiet: Bench,
) -> None:
    """parts.py rule 7: a command given under the lock, taken with the lock OFF that followed
    it (the lines thread was busy with other rotors between the two words), is still a word
    given under the lock: the part it turned on does not turn the rotor once unlocked."""
    bench = quiet
    bench.rot.submit(Lock(True, origin=WHO), "lock ON")
    bench.v._take()
    bench.rest()
    bench.rot.submit(QUIET_ON, "sweep")
    bench.rot.submit(Lock(False, origin=WHO), "lock OFF")  # one batch with the command
    bench.v._take()
    bench.rest()
    assert_still(bench)


def test_a_part_turned_on_between_a_lock_on_and_off_of_one_batch_stays_still(quiet: Bench) -> None:
    """The same, with the lock ON in that batch too: lock ON, the command, lock OFF."""
    bench = quiet
    bench.rest()
    bench.rot.submit(Lock(True, origin=WHO), "lock ON")
    bench.rot.submit(QUIET_ON, "sweep")
    bench.rot.submit(Lock(False, origin=WHO), "lock OFF")
    bench.v._take()
    bench.rest()
    assert_still(bench)


def test_a_command_after_the_release_in_the_same_batch_is_taken(quiet: Bench) -> None:
    """The user's word after the lock OFF is a word given unlocked: it turns the rotor."""
    bench = quiet
    bench.rot.submit(Lock(True, origin=WHO), "lock ON")
    bench.v._take()
    bench.rest()
    bench.rot.submit(QUIET_ON, "sweep")
    bench.rot.submit(Lock(False, origin=WHO), "lock OFF")
    bench.rot.submit(QUIET_ON, "sweep")
    bench.v._take()
    bench.v.run_until(lambda h: abs(h.truth().az_deg - START_AZ) > 5, 10, "turned on again")


def test_a_stop_taken_with_a_command_put_before_it_ends_the_part_it_turned_on(quiet: Bench) -> None:
    """A STOP always wins: a command that says it does not move, put just before the stop and
    taken in one batch with it, turns on no part that turns the rotor after the stop."""
    bench = quiet
    bench.rest()
    bench.rot.submit(QUIET_ON, "sweep")
    bench.rot.submit(Stop(Source.MQTT, WHO), "stop")
    bench.v._take()
    bench.rest()
    assert_still(bench)


def test_a_part_turned_on_by_a_command_a_clearing_release_came_after_stays_still(
    quiet: Bench,
) -> None:
    """A stop from the stop lane holds the rotator until the main connection catches up; that
    connection lost, the release clears what was put before it (mailbox.py rule 6: it may be an
    older word, delivered late). A command that says it does not move, put before that
    release and taken with it, turns on no part that turns the rotor (parts.py rule 7)."""
    bench = quiet
    bench.rest()
    bench.rot.submit(Stop(Source.MQTT, WHO), "stop", hold=1)
    bench.v._take()
    bench.rest()
    bench.rot.submit(QUIET_ON, "sweep")
    bench.rot.release(1, clear=True)
    bench.v._take()
    bench.rest()
    assert_still(bench)


@pytest.mark.parametrize("payload", [b"aim 200", b"label mine"], ids=["moving", "not moving"])
def test_one_judged_before_another_operators_claim_and_put_after_it_is_refused(
    bench: Bench, monkeypatch: pytest.MonkeyPatch, payload: bytes
) -> None:
    """mailbox.py rule 14: G4XYZ's command judged while the lease was free, DL1ABC's claim
    put and taken meanwhile, then the command put: it reached its part under DL1ABC's lease
    (``aim`` turned the rotor to 200, ``label`` changed what the part shows: the lease
    refuses both from another operator). Refused at its put, said and audited."""
    rot = bench.rot

    def claimed() -> None:
        rot.submit(Claim("DL1ABC", 30, origin=WHO), "claim")
        bench.v._take()

    if payload.startswith(b"aim"):
        between_judge_and_put(monkeypatch, rot, claimed)
    else:  # (judged by the lease alone: the claim comes right after it said yes)
        real = rot.operators.refusal

        def refusal(who: str) -> str | None:
            said = real(who)
            monkeypatch.setattr(rot.operators, "refusal", real)
            claimed()
            return said

        monkeypatch.setattr(rot.operators, "refusal", refusal)
    refused: Refused | None = None
    try:
        bench.submit(payload, OTHER)
    except Refused as exc:
        refused = exc
    bench.v._take()
    bench.rest()
    assert bench.sets() == []
    assert bench.v.truth().az_deg == pytest.approx(START_AZ, abs=0.5)
    assert bench.v.status.features["beam"] == {"label": None, "aimed": 0}  # never reached it
    assert refused is not None and refused.code == "leased"
    assert refused.message.startswith("DL1ABC claimed the control lease while it was judged")
    assert bench.events[-1].message == refused.message
    last = bench.audit[-1]
    assert (last.origin, last.result) == (OTHER, f"refused: {refused.message}")
