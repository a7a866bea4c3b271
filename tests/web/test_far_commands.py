"""server.py rule 5: the commands of a rotator far away (the remote's, which waits for its
broker's acknowledgement) run off the console's loop, one at a time in the order they came; a
page's stream and other requests go on while one waits."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator

import pytest

from bridge.core.model import Command, Source, Stop
from bridge.interfaces.mqtt.topics import StationTopics
from bridge.interfaces.web.commands import feed_clock
from bridge.interfaces.web.server import FAR_MOVES, WebConsole
from bridge.interfaces.web.view import RotatorFacts
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from bridge.remote.console import Drawn, RemoteConsoleRotator
from bridge.remote.rotator import Info, RemoteRotator, StationView
from tests.support.clock import FakeClock
from tests.support.console import ConsoleClient
from tests.support.mosquitto import free_port
from tests.support.waiting import slow, wait_until

EZ = REGISTRY["rotorez"]


def new_console() -> WebConsole:
    """A console on a free port, no password, at a station (not listening yet)."""
    return WebConsole(
        "127.0.0.1",
        free_port(),
        password=None,
        frame_ancestors=[],
        station=(55.0, 13.0),
        locator=None,
        satellites=lambda: [],
    )


class FarRotator:
    """A rotator whose commands wait until the test lets them through (a stalled link)."""

    name = "Far"
    spec = EZ
    pointing = Pointing.of(EZ)
    can_track = False
    last_halt_s = 0.0
    halts = 0
    commands_block = True

    def __init__(self, rotator_id: str = "far") -> None:
        self.id = rotator_id
        self.link = threading.Event()  # cleared: the broker does not acknowledge yet
        self.waiting = threading.Event()
        self.carried: list[str] = []

    def submit(
        self, command: Command, described: str | None = None, *, since: int | None = None
    ) -> None:
        assert since == (None if isinstance(command, Stop) else 0)  # (port.py rule 2b)
        self.waiting.set()
        assert self.link.wait(slow(30)), "the test never let the command through"
        self.carried.append("stop" if isinstance(command, Stop) else f"target {command.az_deg:g}")

    def report_refusal(self, *args: object, **kwargs: object) -> None:
        pass


@pytest.fixture
def far() -> Iterator[tuple[FarRotator, WebConsole]]:
    rot = FarRotator()
    console = new_console()
    console.attach(rot, RotatorFacts())  # type: ignore[arg-type]
    console.listen()
    try:
        yield rot, console
    finally:
        rot.link.set()
        console.stop()


def test_a_command_waiting_far_away_holds_up_no_other_request_and_order_is_kept(
    far: tuple[FarRotator, WebConsole],
) -> None:
    rot, console = far
    answers: dict[str, int] = {}

    def post(name: str, **doc: object) -> None:
        client = ConsoleClient(console.port)
        client.session()
        answers[name] = client.command("far", **doc).status

    target = threading.Thread(
        target=post, args=("target",), kwargs={"command": "target", "az": 120}
    )
    target.start()
    assert rot.waiting.wait(slow(10)), "the target never reached the rotator"
    # the loop is free while the target waits for its acknowledgement: a new page is served
    other = ConsoleClient(console.port)
    assert other.session()
    stop = threading.Thread(target=post, args=("stop",), kwargs={"command": "stop"})
    stop.start()
    assert other.get("/api/hello").status == 200  # still answered with two commands waiting
    assert rot.carried == []
    rot.link.set()
    target.join(slow(10))
    stop.join(slow(10))
    wait_until(lambda: len(rot.carried) == 2, 10, "both carried out")
    assert rot.carried == ["target 120", "stop"]  # in the order they came, never overtaken
    assert answers == {"target": 200, "stop": 200}


def test_a_stop_waits_for_the_one_command_under_way_and_the_older_queued_never_go(
    far: tuple[FarRotator, WebConsole],
) -> None:
    """A stalled link: one target waits for its acknowledgement, two more wait behind it, then
    STOP. The STOP goes right after the one under way; the queued targets, older than it, are
    not sent at all (they would turn the rotor after the stop): refused as stale."""
    rot, console = far
    answers: dict[str, int] = {}

    def post(name: str, **doc: object) -> None:
        client = ConsoleClient(console.port)
        client.session()
        answers[name] = client.command("far", **doc).status

    def start(name: str, **doc: object) -> threading.Thread:
        t = threading.Thread(target=post, args=(name,), kwargs=doc)
        t.start()
        return t

    posts = [start("first", command="target", az=120)]
    assert rot.waiting.wait(slow(10)), "the first target never reached the rotator"
    far_thread = console._far["far"]
    for queued, (name, az) in enumerate((("second", 130), ("third", 140)), start=1):
        posts.append(start(name, command="target", az=az))
        wait_until(lambda n=queued: far_thread._work_queue.qsize() == n, 10, f"{name} queued")
    posts.append(start("stop", command="stop"))
    wait_until(lambda: far_thread._work_queue.qsize() == 3, 10, "the stop posted")
    rot.link.set()
    for t in posts:
        t.join(slow(10))
    assert rot.carried == ["target 120", "stop"]
    assert answers == {"first": 200, "second": 409, "third": 409, "stop": 200}


@pytest.fixture
def two() -> Iterator[tuple[FarRotator, FarRotator, WebConsole]]:
    a, b = FarRotator("a"), FarRotator("b")
    console = new_console()
    console.attach(a, RotatorFacts())  # type: ignore[arg-type]
    console.attach(b, RotatorFacts())  # type: ignore[arg-type]
    console.listen()
    try:
        yield a, b, console
    finally:
        a.link.set()
        b.link.set()
        console.stop()


def _post(
    console: WebConsole, rotator: str, answers: dict[str, int], name: str, **doc: object
) -> threading.Thread:
    def run() -> None:
        client = ConsoleClient(console.port)
        client.session()
        answers[name] = client.command(rotator, **doc).status

    t = threading.Thread(target=run)
    t.start()
    return t


def test_a_stop_for_one_far_rotator_never_waits_behind_another_s_commands(
    two: tuple[FarRotator, FarRotator, WebConsole],
) -> None:
    """A's link is stalled with a move under way and another queued; a STOP for B is carried
    out at once and answered, while A's commands still wait."""
    a, b, console = two
    b.link.set()
    answers: dict[str, int] = {}
    posts = [_post(console, "a", answers, "a1", command="target", az=120)]
    assert a.waiting.wait(slow(10)), "A's target never reached the rotator"
    posts.append(_post(console, "a", answers, "a2", command="target", az=130))
    wait_until(lambda: console._far["a"]._work_queue.qsize() == 1, 10, "A's second queued")
    posts.append(_post(console, "b", answers, "stop", command="stop"))
    wait_until(lambda: answers.get("stop") == 200, 10, "B's STOP answered")
    assert b.carried == ["stop"]
    assert a.carried == []  # A's move still waits for its acknowledgement
    a.link.set()
    for t in posts:
        t.join(slow(10))
    assert a.carried == ["target 120", "target 130"]


def test_moves_over_the_bound_for_one_far_rotator_are_refused_at_once_a_stop_never(
    far: tuple[FarRotator, WebConsole],
) -> None:
    rot, console = far
    answers: dict[str, int] = {}
    posts = [_post(console, "far", answers, "m0", command="target", az=100)]
    assert rot.waiting.wait(slow(10)), "the first target never reached the rotator"
    queue = console._far["far"]._work_queue
    for n in range(1, FAR_MOVES):
        posts.append(_post(console, "far", answers, f"m{n}", command="target", az=100 + n))
        wait_until(lambda n=n: queue.qsize() == n, 10, f"move {n} queued")
    client = ConsoleClient(console.port)
    client.session()
    over = client.command("far", command="target", az=200)
    assert (over.status, over.doc["code"]) == (409, "busy")
    assert queue.qsize() == FAR_MOVES - 1  # not queued
    assert answers == {}  # the others still wait
    posts.append(_post(console, "far", answers, "stop", command="stop"))
    wait_until(lambda: queue.qsize() == FAR_MOVES, 10, "the STOP queued, never refused")
    rot.link.set()
    for t in posts:
        t.join(slow(10))
    assert rot.carried == ["target 100", "stop"]
    assert answers["stop"] == 200


class StalledLink:
    """The remote's link to the station's broker (interfaces/mqtt/remote.py), its
    acknowledgements held until the test opens it: one command handed on at a time, as the
    real link's lock keeps them; ``sent`` is what the broker took, in its order."""

    up = True

    def __init__(self) -> None:
        self.open = threading.Event()
        self.waiting = threading.Event()
        self.sent: list[tuple[str, str]] = []
        self._lock = threading.Lock()

    def send(
        self,
        topic: str,
        payload: str,
        operator: str,
        expiry_s: int,
        check: Callable[[], None] | None = None,
        *,
        until_heard: bool = False,
        seen_s: float | None = None,
        after: tuple[str, ...] = (),
        reader: object = None,
        read_s: float | None = None,
    ) -> None:
        with self._lock:  # handed to the broker, one at a time (remote.py rule 9)
            if check is not None:
                check()
            self.sent.append((topic.rsplit("/", 1)[1], payload))
        self.waiting.set()  # its acknowledgement (rule 7)
        assert self.open.wait(slow(30)), "the test never let the link through"


@pytest.fixture
def remote() -> Iterator[tuple[RemoteRotator, StalledLink, WebConsole]]:
    """The remote's console (remote/console.py) before a station's rotator, over a stalled
    link; its other front ends (rotctld) submit to the same ``RemoteRotator``."""
    clock, link = FakeClock(), StalledLink()
    station = StationTopics("rotor")
    view = StationView(clock)  # the station there: its bridge and the rotator online, heard
    view.put(station.bridge_state, b"online")
    view.put(station.bridge_heartbeat, b"1700000000.000")
    view.put(station.rotator("tower").availability, b"online")
    info = Info.parse(
        b'{"name":"tower","model":"rotorez","azimuth_range":[0,360],"elevation_range":null,'
        b'"keep_out":[],"park":null,"options":[]}'
    )
    rot = RemoteRotator("tower", station.rotator("tower"), station, info, view, link, "DL1ABC", 5)
    console = new_console()
    console.attach(RemoteConsoleRotator(rot, Drawn(), view), RotatorFacts())  # type: ignore[arg-type]
    console.listen()
    try:
        yield rot, link, console
    finally:
        link.open.set()
        console.stop()


def test_a_queued_console_move_never_goes_after_a_stop_from_the_remote_s_rotctld(
    remote: tuple[RemoteRotator, StalledLink, WebConsole],
) -> None:
    """port.py rule 2b: a target waits behind the one under way; the operator's logger then
    sends STOP through the remote's rotctld. The queued target, older than that STOP, is not
    sent after it (it would turn the rotor the operator just stopped): refused as stale."""
    rot, link, console = remote
    answers: dict[str, int] = {}
    posts = [_post(console, "tower", answers, "first", command="target", az=120)]
    assert link.waiting.wait(slow(10)), "the first target never reached the link"
    posts.append(_post(console, "tower", answers, "second", command="target", az=130))
    wait_until(lambda: console._far["tower"]._work_queue.qsize() == 1, 10, "the second queued")
    rotctld = threading.Thread(target=rot.submit, args=(Stop(Source.ROTCTLD), "rotctld S"))
    rotctld.start()
    wait_until(lambda: rot.halts == 1, 10, "rotctld's STOP counted")
    link.open.set()
    for t in [*posts, rotctld]:
        t.join(slow(10))
    assert link.sent == [("target", '{"azimuth":120.0}'), ("stop", "stop")]
    assert answers == {"first": 200, "second": 409}


def test_a_console_stop_then_its_target_both_go_far_away(
    remote: tuple[RemoteRotator, StalledLink, WebConsole],
) -> None:
    """port.py rule 2b's other half: the console's own STOP, queued, is no reason to refuse the
    target the page posted after it."""
    rot, link, console = remote
    answers: dict[str, int] = {}
    posts = [_post(console, "tower", answers, "first", command="target", az=120)]
    assert link.waiting.wait(slow(10)), "the first target never reached the link"
    queue = console._far["tower"]._work_queue
    posts.append(_post(console, "tower", answers, "stop", command="stop"))
    wait_until(lambda: queue.qsize() == 1, 10, "the STOP queued")
    posts.append(_post(console, "tower", answers, "then", command="target", az=140))
    wait_until(lambda: queue.qsize() == 2, 10, "the target after it queued")
    link.open.set()
    for t in posts:
        t.join(slow(10))
    assert link.sent == [
        ("target", '{"azimuth":120.0}'),
        ("stop", "stop"),
        ("target", '{"azimuth":140.0}'),
    ]
    assert answers == {"first": 200, "stop": 200, "then": 200}


def test_a_stamped_move_that_grew_too_old_waiting_its_turn_is_not_sent(
    far: tuple[FarRotator, WebConsole], monkeypatch: pytest.MonkeyPatch
) -> None:
    """commands.py rule 6 on the remote's console: a move young when it came, then queued
    behind one the stalled link holds, is judged again when its turn comes: past the age
    limit it is not handed to the broker (it would turn the rotor long after the click)."""
    from bridge.interfaces.web import commands

    monkeypatch.setattr(commands, "MAX_AGE_S", 0.5)
    rot, console = far
    answers: dict[str, int] = {}
    posts = [_post(console, "far", answers, "first", command="target", az=120)]
    assert rot.waiting.wait(slow(10)), "the first target never reached the rotator"
    sent = feed_clock()  # the console's steady clock (commands.py rule 6)
    posts.append(_post(console, "far", answers, "late", command="target", az=130, sent=sent))
    far_thread = console._far["far"]
    wait_until(lambda: far_thread._work_queue.qsize() == 1, 10, "the stamped move queued")
    wait_until(lambda: feed_clock() > sent + 1.0, 10, "the stamped move too old")
    rot.link.set()
    for t in posts:
        t.join(slow(10))
    assert rot.carried == ["target 120"]
    assert answers == {"first": 200, "late": 409}
