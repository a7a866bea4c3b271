"""A motion command judged before a STOP or lock ON never runs after it (docs/architecture.md
rule 11, mailbox.py rule 10), whichever front end's thread brought which. Each test forces the
interleaving: the judge (``Rotator._check``, or ``_check_start`` for a track or follow start)
returns, and before the command is put in the mailbox a halt runs to its end on a thread of its
own (the stop lane, the console); then the command goes on to its put. No timing decides it.
The rotator's front half runs on the virtual bench's session and mailbox (tests/engine/virtual.py),
so what a user would notice is what the emulated controller received.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from bridge.core.errors import Refused
from bridge.core.model import (
    AuditEvent,
    ErrorEvent,
    ErrorKind,
    FollowQso,
    MotionState,
    Nudge,
    Origin,
    Park,
    RotatorStatus,
    Source,
    Stop,
    TakePath,
    Target,
    Toward,
    TrackBody,
)
from bridge.interfaces.mqtt.groups import Group, Member
from bridge.interfaces.mqtt.halts import Halts
from bridge.interfaces.mqtt.topics import Topics
from bridge.interfaces.web.commands import WebCommand, carry_out
from bridge.runtime.rotator import STALE_MESSAGE, Rotator
from bridge.runtime.state_store import StateStore
from bridge.session.config import FollowConfig
from bridge.sky import Sky
from tests.engine.virtual import VirtualRotator
from tests.support.waiting import slow

BERLIN = (52.52, 13.40)
START_AZ = 30.0
ROTCTLD = Origin(Source.ROTCTLD, None, "192.168.1.20")
CONSOLE = "192.168.1.30"


class Bench:
    """A Rotator (the judge every front end calls) on a virtual controller, idle at START_AZ."""

    def __init__(self, tmp_path: Path, model: str = "md01", **settings: object) -> None:
        self.v = VirtualRotator(
            model,
            settings={
                "az_speed_deg_s": 10.0,
                "el_speed_deg_s": 5.0,
                "park_az_deg": 180,
                **settings,
            },
            emulator={"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0, "start_az_deg": START_AZ},
            sky=Sky(*BERLIN),
            follow=FollowConfig(BERLIN, wsjtx=True),
        )
        self.v.run_until(lambda h: h.status.available, 10, "the controller answers")
        self.events: list[ErrorEvent] = []
        self.audit: list[AuditEvent] = []
        self.rot = Rotator(
            self.v.cfg,
            StateStore(tmp_path / "state.json"),
            lambda s: None,
            self.events.append,
            on_audit=self.audit.append,
            station=BERLIN,
        )
        # the rotator's front half on the bench's session; the bench takes the rotator's mailbox
        self.v.mailbox.close()
        self.v.mailbox = self.rot._mailbox
        self.rot._worker.session = self.v.session
        topics = Topics("rotor", {"v": "rotor/v"})

        class Down:  # the main connection is down: the lane's word is the only one
            up = hears = False

            def publish_marker(self, topic: str, payload: str) -> None:
                raise AssertionError("no marker while the main connection is down")

        self.lane = Halts(
            topics, Down(), {"v": self.rot}, lambda: 0.0, retain_is_live=True, on_problem=None
        )

    def close(self) -> None:
        self.rot.operators.stop()
        self.v.close()

    def sets(self) -> list[bytes]:
        """The target frames the controller received."""
        return [f.data for f in self.v.frames("set")]


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[Bench]:
    made = Bench(tmp_path)
    yield made
    made.close()


def on_a_thread(*words: Callable[[], None]) -> None:
    """``words`` in order on another thread, to their end (a front end's thread)."""
    failed: list[BaseException] = []

    def run() -> None:
        try:
            for word in words:
                word()
        except BaseException as exc:  # re-raised on the test's thread
            failed.append(exc)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(slow(10))
    assert not thread.is_alive(), "the halt did not return"
    if failed:
        raise failed[0]


def between_judge_and_put(
    monkeypatch: pytest.MonkeyPatch, rot: Rotator, *words: Callable[[], None]
) -> None:
    """The first motion command judged runs ``words`` on another thread once its judge has
    said yes, before its put."""
    once = [True]

    def hooked(real: Callable[..., object]) -> Callable[..., object]:
        def judged(*args: object) -> object:
            out = real(*args)
            if once[0]:
                once[0] = False
                on_a_thread(*words)
            return out

        return judged

    monkeypatch.setattr(rot, "_check", hooked(rot._check))
    monkeypatch.setattr(rot, "_check_start", hooked(rot._check_start))


def halts(b: Bench) -> dict[str, tuple[Callable[[], None], ...]]:
    rot, lane = b.rot, b.lane

    def lane_stop() -> None:
        lane.on_lane("rotor/v/stop", b"", False, Origin(Source.MQTT, "DL1ABC"))

    def lane_lock_on() -> None:
        lane.on_lane("rotor/v/lock", b"ON", False, Origin(Source.MQTT, "DL1ABC"))

    def console(on: bool | None) -> Callable[[], None]:
        cmd = WebCommand("stop") if on is None else WebCommand("lock", on=on)
        return lambda: carry_out(rot, cmd, CONSOLE)

    return {
        "lane STOP": (lane_stop,),
        "console STOP": (console(None),),
        "lane lock ON, console lock OFF": (lane_lock_on, console(False)),
        "console lock ON, console lock OFF": (console(True), console(False)),
    }


def motions(b: Bench) -> dict[str, Callable[[], None]]:
    rot = b.rot
    return {
        "target": lambda: rot.submit(Target(200.0, None, Source.ROTCTLD, origin=ROTCTLD)),
        "park": lambda: rot.submit(Park(source=Source.PST), "pst park"),
        "track": lambda: rot.submit(TrackBody("sun"), "track sun"),
        "follow": lambda: rot.submit(FollowQso(True), "follow on"),
    }


def served(b: Bench) -> None:
    """The lines thread takes the batch; WSJT-X names a partner (what following would turn
    to); the rotor has time to turn."""
    b.v._take()
    b.v.heard("JA1ABC", "PM95")
    b.v.run_for(30.0)


HALTS = [
    "lane STOP",
    "console STOP",
    "lane lock ON, console lock OFF",
    "console lock ON, console lock OFF",
]


@pytest.mark.parametrize("halt", HALTS)
@pytest.mark.parametrize("motion", ["target", "park", "track", "follow"])
def test_a_motion_judged_before_a_halt_never_runs_after_it(
    bench: Bench, monkeypatch: pytest.MonkeyPatch, halt: str, motion: str
) -> None:
    """Judged (lock OFF, the link up), then a STOP, or a lock ON and OFF, from another thread,
    then put: nothing turns the rotor (before: the batch had the halt and the motion after it,
    and the rotor set off after the STOP or the lock ON)."""
    between_judge_and_put(monkeypatch, bench.rot, *halts(bench)[halt])
    try:
        motions(bench)[motion]()
        refused: Refused | None = None
    except Refused as exc:
        refused = exc
    batch = bench.rot._mailbox.take()
    bench.v._do(bench.v.session.commands(batch, bench.v.now))
    served(bench)
    assert bench.sets() == []  # no target frame reached the controller
    assert (batch.target, batch.track, batch.follow) == (None, None, None)
    assert abs(bench.v.truth().az_deg - START_AZ) <= 0.5 and not bench.v.truth().is_moving
    assert bench.v.status.tracking is None and bench.v.status.following is None
    # the front end was told, R/error says why, and the audit trail has it refused
    assert refused is not None and refused.code == "stale" and refused.message == STALE_MESSAGE
    said = [e for e in bench.events if e.kind is ErrorKind.REFUSED]
    assert [e.message for e in said] == [STALE_MESSAGE]
    assert bench.audit[-1].result == f"refused: {STALE_MESSAGE}"


@pytest.mark.parametrize(
    "halt",
    ["lane STOP", "console STOP", "console lock ON, console lock OFF"],
)
def test_a_target_judged_after_the_halt_goes_out(bench: Bench, halt: str) -> None:
    """The same halts on their thread, then a target judged on another: it is newer than them
    and is carried out after them."""
    on_a_thread(*halts(bench)[halt])
    motions(bench)["target"]()
    batch = bench.rot._mailbox.take()
    assert batch.target is not None and (batch.stop is not None or batch.lock_on)
    bench.v._do(bench.v.session.commands(batch, bench.v.now))
    bench.v.run_until(lambda h: h.state is MotionState.IDLE and h.truth().az_deg > 190, 60)
    assert len(bench.sets()) == 1 and abs(bench.v.truth().az_deg - 200.0) <= 0.5
    assert not [e for e in bench.events if e.kind is ErrorKind.REFUSED]
    assert bench.audit[-1].result == "executed"


def test_following_off_and_tracking_off_are_never_overtaken(
    bench: Bench, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An OFF is never refused (docs/architecture.md rule 11), a halt around it or not."""
    rot = bench.rot
    box = rot._mailbox
    real_track, real_follow = box.put_track, box.put_follow
    stop = halts(bench)["console STOP"]

    def put_track(*args: object, **kw: object) -> bool:
        on_a_thread(*stop)
        return real_track(*args, **kw)  # type: ignore[arg-type]

    def put_follow(*args: object, **kw: object) -> bool:
        on_a_thread(*stop)
        return real_follow(*args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(box, "put_track", put_track)
    monkeypatch.setattr(box, "put_follow", put_follow)
    rot.submit(TrackBody("off"), "track off")
    track = box.take().track
    assert track is not None and track.body is None and track.lookup is None
    rot.submit(FollowQso(False), "follow off")
    follow = box.take().follow
    assert follow is not None and not follow.on
    assert not bench.events
    assert [a.result for a in bench.audit] == ["executed"] * 4  # two stops, two OFFs


# -- a command relative to the target, after a stop (mailbox.py rule 10's count) --------------
MQTT = Origin(Source.MQTT)


def stopped_on_the_way(bench: Bench, target: Target | Toward, taken: bool) -> float:
    """Turning to ``target``, then a STOP, taken by the session (``taken``) or still in the
    mailbox; the bearing the STOP came at."""
    bench.rot.submit(target, "on its way")
    bench.v._take()
    bench.v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 60, 30)
    at_stop = bench.v.truth().az_deg
    bench.rot.submit(Stop(Source.MQTT, MQTT), "stop")
    if taken:
        bench.v._take()  # (a half-duplex SPID: the stop waits for the reply in flight, if any)
        assert bench.v.status.target_az_deg is None  # what the STOP dropped, shown at once
    return at_stop


@pytest.mark.parametrize("taken", [False, True])
def test_a_nudge_after_a_stop_is_from_where_the_rotor_stopped(bench: Bench, taken: bool) -> None:
    """An attack pass: a STOP and then +10, both read before the lines thread took the STOP
    (paho's thread hands on two messages back to back): the nudge was made from the status
    that still showed the target the STOP dropped (150), and the rotor turned on to 160."""
    at_stop = stopped_on_the_way(bench, Target(150.0, None, Source.MQTT, origin=MQTT), taken)
    bench.rot.submit(Nudge(10.0, source=Source.MQTT, origin=MQTT), "nudge +10")
    bench.v._take()
    bench.v.run_for(30)
    end = bench.v.truth().az_deg
    assert abs(end - (at_stop + 10)) <= 3, f"STOP at {at_stop:.1f}, then +10 ended at {end:.1f}"
    assert not bench.v.truth().is_moving


@pytest.mark.parametrize("taken", [False, True])
def test_the_other_path_after_a_stop_is_refused(bench: Bench, taken: bool) -> None:
    """The same for ``{"path": "long"}``: the place of a target a STOP dropped is no target."""
    toward = Toward(-33.9, 18.4, source=Source.MQTT, origin=MQTT)  # Cape Town: 175, short
    stopped_on_the_way(bench, toward, taken)
    with pytest.raises(Refused) as exc:
        bench.rot.submit(TakePath(True, source=Source.MQTT, origin=MQTT), "take path long")
    assert exc.value.message == "no locator or coordinate target to take the other path to"
    bench.v._take()
    bench.v.run_for(30)
    assert not bench.v.truth().is_moving and len(bench.sets()) == 1


def test_a_stop_while_a_nudge_is_judged_overtakes_it(
    bench: Bench, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A review: a STOP put (another front end's thread) after the nudge read the status and
    before its put: the nudge was put as judged after it, and the rotor turned on to 160. The
    halt count read before the status goes with it to the put, which drops it."""
    stopped_on_the_way(bench, Target(150.0, None, Source.MQTT, origin=MQTT), taken=True)
    seen = bench.rot._seen

    def then_a_stop() -> tuple[RotatorStatus, bool]:
        out = seen()
        on_a_thread(lambda: bench.rot.submit(Stop(Source.ROTCTLD), "rotctld S"))
        return out

    monkeypatch.setattr(bench.rot, "_seen", then_a_stop)
    with pytest.raises(Refused) as exc:
        bench.rot.submit(Nudge(10.0, source=Source.MQTT, origin=MQTT), "nudge +10")
    assert exc.value.message == STALE_MESSAGE
    bench.v._take()
    bench.v.run_for(30)
    assert not bench.v.truth().is_moving and len(bench.sets()) == 1  # the first target's only


def test_a_halt_a_connection_read_stands_for_the_express_s_of_its_kind_only(bench: Bench) -> None:
    """express.py rule 11 (halts.py ``read_since``): a connection that read a STOP, and has had
    its topics since, stands for a stop only the express read; only a lock ON it read stands
    for a lock ON (a review: a STOP read after a lock ON only the express had would have left
    the rotator unlocked). A connection with a break since stands for nothing."""

    def always(via: str, t: float) -> bool:  # subscribed without a break since t
        return True

    def broke(via: str, t: float) -> bool:
        return False

    lane = bench.lane
    assert not lane.read_since("v", "stop", always)
    lane.on_lane("rotor/v/stop", b"STOP", False)
    assert lane.read_since("v", "stop", always) and not lane.read_since("v", "lock", always)
    assert not lane.read_since("v", "stop", broke)
    lane.on_lane("rotor/v/lock", b"ON", False)
    assert lane.read_since("v", "lock", always)


def test_a_lock_on_the_lock_lane_read_stands_for_no_stop(bench: Bench) -> None:
    """Review 108: the lock lane subscribes to ``R/lock`` alone (lastword.py rule 16), so a lock
    ON it read, and its topics kept since, says nothing of a STOP only the express read: that
    STOP is the bridge's to carry out (it had been dropped, and the rotor turned on)."""

    def lock_lane_only(via: str, t: float) -> bool:  # the main connection and stop lane away
        return via == "lock"

    halts = bench.lane
    halts.on_lane("rotor/v/lock", b"ON", False)
    assert halts.read_since("v", "lock", lock_lane_only)  # (it stands for a lock ON)
    assert not halts.read_since("v", "stop", lock_lane_only)


def test_a_group_s_stop_read_on_the_main_connection_stands_for_each_member_s(
    bench: Bench,
) -> None:
    """A review: a group's STOP read on the main connection was not kept for ``read_since``
    (the lane's was), so the express's report of the same stop gave each member a second one,
    which could drop a target sent right after it."""
    halts = bench.lane
    halts._publisher.publish_marker = lambda topic, payload: None  # type: ignore[method-assign]
    halts._groups["g"] = Group("g", "G", (Member("v"),))
    assert not halts.read_since("v", "stop", lambda via, t: via == "main")
    halts.main_group_stop("g", "rotor/group/g/stop", "STOP", False)
    assert halts.read_since("v", "stop", lambda via, t: via == "main")


def test_a_call_asked_while_locked_never_turns_the_rotor_after_the_lock_off(bench: Bench) -> None:
    """mailbox.py rule 10a with the lock: the DX cluster's call (``R/target {"call": ...}``) is
    asked, then looked up and judged on a thread of its own. Asked while the lock was ON, with
    the lock OFF published right after it and read before its look-up ended, it was judged
    after the OFF and turned the rotor: a plain target published at its place was refused by
    the lock. The lock OFF is the later word: the call asked before it is not carried out."""
    rot = bench.rot
    carry_out(rot, WebCommand("lock", on=True), CONSOLE)
    since, ticket = rot.halts, rot.ticket()  # the call asked (interfaces/dxcluster/client.py)
    carry_out(rot, WebCommand("lock", on=False), CONSOLE)  # the OFF, read meanwhile
    with pytest.raises(Refused):
        rot.submit(
            Toward(35.7, 139.7, "PM95vq", source=Source.DXCLUSTER),
            "call",
            since=since,
            ticket=ticket,
        )
    batch = rot._mailbox.take()
    bench.v._do(bench.v.session.commands(batch, bench.v.now))
    served(bench)
    assert bench.sets() == []
    assert abs(bench.v.truth().az_deg - START_AZ) <= 0.5


def test_an_am1_whose_ap1_came_before_a_stop_never_turns_after_it(
    bench: Bench, monkeypatch: pytest.MonkeyPatch
) -> None:
    """gs232/ package rule 10 (review 102, 090451a): the AP1's bearing is kept with the halt
    count and an AM1 after a STOP is refused. The count is read at the AM1 and the target
    submitted after: a STOP from the stop lane in between (another thread, the interpreter
    lock switched there) is counted after the check and before the submit takes its own
    count, so the AP1's bearing, given before the STOP, went out after it. The count kept with
    the bearing is now the submit's ``since`` (mailbox.py rule 10): the STOP overtakes it."""
    from bridge.interfaces.gs232 import Dcu1Session

    dcu = Dcu1Session(bench.rot)
    assert dcu.feed(b"AP1200;") == [b""]
    real = bench.rot.submit
    once = [True]

    def submit(command: object, *args: object, **kw: object) -> None:
        if once[0] and isinstance(command, Target):
            once[0] = False
            on_a_thread(*halts(bench)["lane STOP"])  # after the AM1's check, before its put
        real(command, *args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(bench.rot, "submit", submit)
    dcu.feed(b"AM1;")
    batch = bench.rot._mailbox.take()
    bench.v._do(bench.v.session.commands(batch, bench.v.now))
    served(bench)
    assert bench.sets() == []  # the AP1's bearing never reached the controller
    assert abs(bench.v.truth().az_deg - START_AZ) <= 0.5
