"""The control lease as the judge applies it, and the audit trail of every command judged; in
virtual time (a wall clock that is a number, a timer that fires when the test says). No port is
opened: the rotator is offline, so a target the lease lets through is refused for the link."""

from __future__ import annotations

import json
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bridge.app import worker_config
from bridge.core.errors import Refused
from bridge.core.model import (
    AuditEvent,
    Claim,
    Control,
    ErrorEvent,
    Lock,
    Origin,
    Park,
    Release,
    Source,
    Stop,
    Target,
    TrackBody,
)
from bridge.runtime.operators import LEASE_CHECK_S, Operators
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.session.mailbox import Mailbox
from bridge.settings import RotatorSettings
from bridge.sky import Sky

T0 = 1_790_000_000.0  # 14:13:20 UTC
HOLDER = Origin(Source.MQTT, "DL1ABC")
OTHER = Origin(Source.MQTT, "G4XYZ")
ROTCTLD = Origin(Source.ROTCTLD, None, "192.168.1.20")


class Clock:
    def __init__(self) -> None:
        self.now = T0

    def __call__(self) -> float:
        return self.now


class Timers:
    """Timers that fire when the test says (virtual time)."""

    def __init__(self) -> None:
        self.armed: list[tuple[float, Callable[[], None], list[bool]]] = []

    def __call__(self, delay_s: float, fire: Callable[[], None]) -> Timers.One:
        one = Timers.One()
        self.armed.append((delay_s, fire, one.cancelled))
        return one

    class One:
        def __init__(self) -> None:
            self.cancelled = [False]

        def cancel(self) -> None:
            self.cancelled[0] = True

    def live(self) -> list[tuple[float, Callable[[], None]]]:
        return [(d, f) for d, f, c in self.armed if not c[0]]


def rotator(tmp_path: Path, clock: Clock) -> tuple[Rotator, list[AuditEvent], list[ErrorEvent]]:
    audit: list[AuditEvent] = []
    events: list[ErrorEvent] = []
    settings = RotatorSettings(id="t", model="rotorez", port="/dev/null", park_az_deg=0)
    cfg = worker_config(settings)
    store = StateStore(tmp_path / "state.json")
    rot = Rotator(cfg, store, lambda s: None, events.append, wall=clock, on_audit=audit.append)
    return rot, audit, events


def refused(run: Callable[[], None]) -> str:
    with pytest.raises(Refused) as exc:
        run()
    return str(exc.value.code)


def test_the_holders_targets_pass_anyone_elses_are_refused_naming_holder_and_end(
    tmp_path: Path,
) -> None:
    clock = Clock()
    rot, audit, events = rotator(tmp_path, clock)
    rot.submit(Claim("DL1ABC", 30, origin=HOLDER), "claim")
    clock.now += 300
    assert refused(lambda: rot.submit(Target(120, origin=OTHER), "target 120")) == "leased"
    assert events[-1].message == (
        "DL1ABC holds the rotator until 14:43 UTC (25 min left): only they may turn it "
        "(control lease)"
    )
    assert refused(lambda: rot.submit(Target(120, source=Source.ROTCTLD, origin=ROTCTLD))) == (
        "leased"
    )
    assert (
        refused(lambda: rot.submit(Park(source=Source.PST, origin=OTHER), "pst park")) == "leased"
    )
    assert refused(lambda: rot.submit(TrackBody("sun", origin=OTHER), "track sun")) in (
        "leased",
        "unsupported",  # no station here: tracking is refused before the lease is asked
    )
    # the holder's target passes the lease (and is refused only for the link: offline here)
    assert refused(lambda: rot.submit(Target(120, origin=HOLDER), "target 120")) == "offline"
    # a stop, a lock ON, tracking OFF: never refused, whoever sends them
    rot.submit(Stop(Source.MQTT, OTHER), "stop")
    rot.submit(Lock(True, origin=OTHER))
    rot.submit(Lock(False, origin=OTHER))
    rot.submit(TrackBody("off", origin=OTHER), "track off")
    rows = [(a.origin.who, a.command, a.result.split(":")[0]) for a in audit]
    assert rows == [
        ("DL1ABC", "claim", "executed"),
        ("G4XYZ", "target 120", "refused"),
        ("rotctld 192.168.1.20", "target az 120", "refused"),
        ("G4XYZ", "pst park", "refused"),
        ("G4XYZ", "track sun", "refused"),
        ("DL1ABC", "target 120", "refused"),  # offline
        ("G4XYZ", "stop", "executed"),
        ("G4XYZ", "lock ON", "executed"),
        ("G4XYZ", "lock OFF", "executed"),
        ("G4XYZ", "track off", "executed"),
    ]
    assert audit[1].result.startswith("refused: DL1ABC holds the rotator until 14:43 UTC")
    assert audit[2].origin.interface is Source.ROTCTLD and audit[2].origin.peer == "192.168.1.20"


def test_a_claim_while_held_is_refused_and_anyone_may_release(tmp_path: Path) -> None:
    clock = Clock()
    rot, audit, events = rotator(tmp_path, clock)
    rot.submit(Claim("DL1ABC", 30, origin=HOLDER), "claim")
    assert refused(lambda: rot.submit(Claim("G4XYZ", 10, origin=OTHER), "claim")) == "invalid"
    assert "DL1ABC holds the rotator until 14:43 UTC (30 min left)" in events[-1].message
    assert refused(lambda: rot.submit(Claim("G4XYZ", 0, origin=OTHER), "claim")) == "invalid"
    assert rot.operators.holder == Control("DL1ABC", T0 + 1800)
    rot.submit(Release(origin=OTHER), "release")  # the station owner's button, say
    assert rot.operators.holder is None
    assert refused(lambda: rot.submit(Target(10, origin=OTHER))) == "offline"  # free
    assert [a.result.split(":")[0] for a in audit] == [
        "executed",
        "refused",
        "refused",
        "executed",
        "refused",
    ]


def test_the_lease_survives_a_restart(tmp_path: Path) -> None:
    clock = Clock()
    rot, _, _ = rotator(tmp_path, clock)
    rot.submit(Claim("DL1ABC", 30, origin=HOLDER), "claim")
    rot.operators.stop()
    rot._store.flush()  # the save runs on the store's writer thread
    kept = json.loads((tmp_path / "state.json").read_text())["rotators"]["t"]["lease"]
    assert kept == {"operator": "DL1ABC", "until": T0 + 1800}
    again, _, _ = rotator(tmp_path, clock)
    assert again.operators.holder == Control("DL1ABC", T0 + 1800)
    assert refused(lambda: again.submit(Target(10, origin=OTHER))) == "leased"


def test_a_flood_of_renewed_claims_is_one_save_of_the_newest(tmp_path: Path) -> None:
    """Rule 1, an attack pass: 1,500 renewing claims queued as many writes of the state file,
    each with its fsync, and a lock ON's save waited a minute behind them on an SD card."""
    clock = Clock()
    rot, _, _ = rotator(tmp_path, clock)
    store = rot._store
    gate = threading.Event()
    store.later(gate.wait)  # the writer busy (a slow disk) while the claims come
    written: list[bytes] = []
    write = store._write

    def counted(path: Path, **kw: Any) -> None:
        write(path, **kw)
        written.append((tmp_path / "state.json").read_bytes())

    store._write = counted  # type: ignore[method-assign]
    for minutes in range(1, 51):  # the holder renews, and renews
        rot.submit(Claim("DL1ABC", minutes, origin=HOLDER), "claim")
    gate.set()
    store.flush()
    assert len(written) == 1
    kept = json.loads(written[0])["rotators"]["t"]["lease"]
    assert kept == {"operator": "DL1ABC", "until": T0 + 50 * 60}  # the newest


def test_the_lease_ends_by_itself_and_the_status_is_told(tmp_path: Path) -> None:
    clock, timers, mailbox = Clock(), Timers(), Mailbox()
    store = StateStore(tmp_path / "state.json")
    ops = Operators(
        "t",
        store,
        mailbox,
        wall=clock,
        bearing=lambda: None,
        report=lambda *a: None,
        timer=timers,
    )
    ops.claim("DL1ABC", 2, HOLDER)
    assert mailbox.take().control == Control("DL1ABC", T0 + 120)
    [(delay_s, fire)] = timers.live()
    assert delay_s == LEASE_CHECK_S  # (rule 2: it looks at the wall clock at least so often)
    clock.now += 119.5  # the wall clock was set forward a little less than the timer ran
    fire()  # early: nothing ends, a new timer for the rest
    assert ops.holder is not None and not mailbox.take()
    [(rest_s, fire)] = timers.live()[-1:]
    assert rest_s == pytest.approx(0.5)
    clock.now += 0.5
    fire()
    batch = mailbox.take()
    assert batch.control_set and batch.control is None  # the status says: free
    assert ops.holder is None and ops.refusal("G4XYZ") is None
    store.flush()
    assert "lease" not in json.loads((tmp_path / "state.json").read_text())["rotators"]["t"]
    mailbox.close()


def test_a_wall_clock_stepped_past_the_end_ends_the_lease_for_the_judge_and_the_status_alike(
    tmp_path: Path,
) -> None:
    """An attack pass: NTP stepped the wall clock an hour forward (a board without a clock
    chip, after a restart that restored the lease); the judge let anyone turn the rotor while
    R/control, R/status and the console named the holder until the timer fired, which waits
    on the monotonic clock: up to the whole lease later. The judge's own look ends it, said
    and audited; the timer looks at least every LEASE_CHECK_S."""
    clock, timers, mailbox = Clock(), Timers(), Mailbox()
    audit: list[AuditEvent] = []
    ops = Operators(
        "t", StateStore(tmp_path / "state.json"), mailbox, wall=clock, bearing=lambda: None,
        report=lambda *a: None, timer=timers, on_audit=audit.append,
    )  # fmt: skip
    ops.claim("DL1ABC", 30, HOLDER)
    assert mailbox.take().control == Control("DL1ABC", T0 + 1800)
    assert [d for d, _ in timers.live()] == [LEASE_CHECK_S]
    clock.now += 3600
    assert ops.refusal("G4XYZ") is None  # free for the judge...
    batch = mailbox.take()
    assert batch.control_set and batch.control is None  # ... and for the status
    assert [(a.origin.who, a.command) for a in audit] == [("DL1ABC", "control expired")]
    assert timers.live() == []
    mailbox.close()


def test_a_release_or_a_claim_over_a_lease_the_wall_clock_ended_ends_it_first(
    tmp_path: Path,
) -> None:
    """A review: a release within the minute after the clock stepped past the end found it
    free, cancelled the timer and told the status nothing: R/control named the holder for
    good, the end in no audit trail; a claim over it replaced it unaudited."""
    for then in ("release", "claim"):
        clock, timers, mailbox = Clock(), Timers(), Mailbox()
        audit: list[AuditEvent] = []
        ops = Operators(
            "t", StateStore(tmp_path / f"{then}.json"), mailbox, wall=clock,
            bearing=lambda: None, report=lambda *a: None, timer=timers, on_audit=audit.append,
        )  # fmt: skip
        ops.claim("DL1ABC", 30, HOLDER)
        assert mailbox.take().control == Control("DL1ABC", T0 + 1800)
        clock.now += 3600  # NTP steps the wall clock forward
        if then == "release":
            assert ops.release(OTHER) is None  # (it had ended: nothing to release)
            batch = mailbox.take()
            assert batch.control_set and batch.control is None
        else:
            ops.claim("G4XYZ", 10, OTHER)
            assert mailbox.take().control == Control("G4XYZ", T0 + 3600 + 600)
        assert [(a.origin.who, a.command) for a in audit] == [("DL1ABC", "control expired")]
        mailbox.close()


def test_a_kept_lease_that_ended_while_the_bridge_was_stopped_is_audited_and_forgotten(
    tmp_path: Path,
) -> None:
    """An attack pass: it was neither audited nor taken out of the state file (where a clock
    set back at a later boot made it hold again)."""
    clock = Clock()
    rot, _, _ = rotator(tmp_path, clock)
    rot.submit(Claim("DL1ABC", 30, origin=HOLDER), "claim")
    rot.operators.stop()
    rot._store.flush()
    clock.now += 2 * 3600  # stopped for two hours
    again, audit, _ = rotator(tmp_path, clock)
    again.operators.start()
    again._store.flush()
    assert again.operators.holder is None
    assert "lease" not in json.loads((tmp_path / "state.json").read_text())["rotators"]["t"]
    assert [(a.origin.who, a.command) for a in audit] == [("DL1ABC", "control expired")]
    clock.now -= 2 * 3600  # the clock set back: nothing left to revive
    third, _, _ = rotator(tmp_path, clock)
    assert third.operators.holder is None
    again.operators.stop()


def test_input_refused_before_it_became_a_command_is_audited_when_its_sender_is_known(
    tmp_path: Path,
) -> None:
    rot, audit, events = rotator(tmp_path, Clock())
    rot.report_refusal("bad payload", "target 'north'", origin=OTHER)  # e.g. a bad payload
    rot.report_refusal("bad payload", "target 'north'")  # nobody known: R/error only
    assert [e.message for e in events] == ["bad payload", "bad payload"]
    assert [(a.origin.who, a.command, a.result) for a in audit] == [
        ("G4XYZ", "target 'north'", "refused: bad payload")
    ]


@pytest.mark.parametrize(
    "kept",
    [
        '{"operator": "DL1ABC", "until": 1e20}',  # past what a date can say
        '{"operator": "DL1ABC", "until": Infinity}',
        '{"operator": "DL1ABC", "until": 1' + "0" * 400 + "}",  # an int no float holds
        '{"operator": "DL1ABC", "until": 4070908800}',  # 2099: more than a claim can ask
        '{"operator": "DL1\\nABC", "until": 1790000600}',  # not an operator's name
        '{"operator": "", "until": 1790000600}',
        '{"operator": "mqtt", "until": 1790000600}',  # an interface: every plain MQTT client
        '{"operator": "rotctld 127.0.0.1", "until": 1790000600}',
    ],
)
def test_a_kept_lease_no_claim_could_have_made_is_ignored(tmp_path: Path, kept: str) -> None:
    """state_store.py rule 6, lease.py rule 6: a hand-edited or damaged state file neither
    holds the rotator for years nor makes every command fail (a date out of range)."""
    (tmp_path / "state.json").write_text('{"rotators": {"t": {"lease": ' + kept + "}}}")
    clock = Clock()
    rot, _, events = rotator(tmp_path, clock)
    assert rot.operators.holder is None
    assert refused(lambda: rot.submit(Target(10, origin=OTHER))) == "offline"  # not leased
    assert "holds the rotator" not in events[-1].message


def test_a_kept_lease_with_the_clock_set_back_ends_within_a_claims_longest(
    tmp_path: Path,
) -> None:
    """A lease kept across a restart while the wall clock went back (a Raspberry Pi boots
    with the time it shut down at): it has at most MAX_MINUTES left."""
    clock = Clock()
    rot, _, _ = rotator(tmp_path, clock)
    rot.submit(Claim("DL1ABC", 30, origin=HOLDER), "claim")
    rot.operators.stop()
    rot._store.flush()
    clock.now -= 3 * 86400
    again, _, _ = rotator(tmp_path, clock)
    assert again.operators.holder is None
    again.operators.start()  # gone from the file: the clock put right later revives nothing
    again._store.flush()
    assert "lease" not in json.loads((tmp_path / "state.json").read_text())["rotators"]["t"]
    again.operators.stop()


def test_tracking_is_a_motion_command_the_lease_judges(tmp_path: Path) -> None:
    """lease.py rule 5: another operator's ``track sun`` is refused for the lease (the earlier
    test's rotator has no station, so its tracking is refused before the lease is asked)."""
    clock = Clock()
    events: list[ErrorEvent] = []
    settings = RotatorSettings(id="t", model="md01", port="/dev/null", park_az_deg=0)
    store = StateStore(tmp_path / "state.json")
    cfg = worker_config(settings, Sky(52.52, 13.29))
    rot = Rotator(cfg, store, lambda s: None, events.append, wall=clock)
    rot.submit(Claim("DL1ABC", 30, origin=HOLDER), "claim")
    assert refused(lambda: rot.submit(TrackBody("sun", origin=OTHER), "track sun")) == "leased"
    assert events[-1].message.startswith("DL1ABC holds the rotator")
    assert refused(lambda: rot.submit(TrackBody("sun", origin=HOLDER), "track sun")) == (
        "offline"  # the holder's passes the lease (no controller here)
    )
