"""server.py rule 10: a nudge (a command the judge makes from the status) posted while the
command before it is still on its way to the lines thread waits for it, then is judged as it
came; a STOP or a newer click of the page's meanwhile makes it stale. The rotator here is a
scripted one: the test says when what is on its way shows."""

from __future__ import annotations

import math
import threading
from collections.abc import Iterator

import pytest

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import Command, Nudge, Stop, Target
from bridge.interfaces.web import server
from bridge.interfaces.web.server import WebConsole
from bridge.interfaces.web.view import RotatorFacts
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from bridge.runtime.rotator import ON_ITS_WAY_MESSAGE
from tests.support.console import Answer, ConsoleClient
from tests.support.mosquitto import free_port
from tests.support.waiting import slow, wait_until

EZ = REGISTRY["rotorez"]


class NearRotator:
    """The station's own rotator as far as the console sees it, with a motion command on its
    way while ``way`` is set; its judge refuses a nudge then, as runtime/rotator.py's does."""

    name = "Near"
    spec = EZ
    pointing = Pointing.of(EZ)
    can_track = False
    commands_block = False

    def __init__(self) -> None:
        self.id = "near"
        self.way = threading.Event()
        self.looks = 0
        self.halts = 0
        self.last_halt_s = -math.inf
        self.carried: list[str] = []

    def on_its_way(self) -> bool:
        self.looks += 1
        return self.way.is_set()

    def submit(
        self, command: Command, described: str | None = None, *, since: int | None = None
    ) -> None:
        if isinstance(command, Stop):
            self.carried.append("stop")
        elif isinstance(command, Nudge):
            if self.way.is_set():
                raise Refused(RefusalCode.STALE, ON_ITS_WAY_MESSAGE)
            self.carried.append(f"nudge {command.d_az_deg:+g}")
        elif isinstance(command, Target):
            self.carried.append(f"target {command.az_deg:g}")

    def report_refusal(self, *args: object, **kwargs: object) -> None:
        pass


@pytest.fixture
def near() -> Iterator[tuple[NearRotator, ConsoleClient]]:
    rot = NearRotator()
    console = WebConsole(
        "127.0.0.1",
        free_port(),
        password=None,
        frame_ancestors=[],
        station=(55.0, 13.0),
        locator=None,
        satellites=lambda: [],
    )
    console.attach(rot, RotatorFacts())  # type: ignore[arg-type]
    console.listen()
    client = ConsoleClient(console.port)
    client.session()
    try:
        yield rot, client
    finally:
        rot.way.clear()
        console.stop()


def _posted(client: ConsoleClient, answers: list[Answer], **doc: object) -> threading.Thread:
    """``doc`` posted on a thread of its own (the POST is answered once it is judged)."""
    other = ConsoleClient(client.port)
    other.token = client.token
    t = threading.Thread(target=lambda: answers.append(other.command("near", **doc)))
    t.start()
    return t


def _waiting(rot: NearRotator) -> None:
    """The console holds the nudge: it has looked more than once, and sent nothing."""
    wait_until(lambda: rot.looks >= 3, 10, "the console waits for what is on its way")
    assert rot.carried == []


def test_a_nudge_right_after_a_command_waits_for_it_and_then_counts(
    near: tuple[NearRotator, ConsoleClient],
) -> None:
    """A second click came before the lines thread took the first: refused "send it again"
    (a failed CI run); now it waits and goes."""
    rot, client = near
    rot.way.set()
    answers: list[Answer] = []
    nudge = _posted(client, answers, command="nudge", d_az=5, page="p", seq=2)
    _waiting(rot)
    rot.way.clear()  # the lines thread took the command before it
    nudge.join(slow(10))
    assert [a.status for a in answers] == [200]
    assert rot.carried == ["nudge +5"]


def test_a_stop_while_a_nudge_waits_leaves_the_nudge_unsent(
    near: tuple[NearRotator, ConsoleClient],
) -> None:
    rot, client = near
    rot.way.set()
    answers: list[Answer] = []
    nudge = _posted(client, answers, command="nudge", d_az=5)
    _waiting(rot)
    assert client.command("near", command="stop").status == 200
    rot.way.clear()
    nudge.join(slow(10))
    assert [(a.status, a.doc.get("code")) for a in answers] == [(409, "stale")]
    assert rot.carried == ["stop"]


def test_a_newer_target_of_the_page_while_a_nudge_waits_is_not_overtaken_by_it(
    near: tuple[NearRotator, ConsoleClient],
) -> None:
    rot, client = near
    rot.way.set()
    answers: list[Answer] = []
    nudge = _posted(client, answers, command="nudge", d_az=5, page="p", seq=2)
    _waiting(rot)
    assert client.command("near", command="target", az=90, page="p", seq=3).status == 200
    rot.way.clear()
    nudge.join(slow(10))
    assert [(a.status, a.doc.get("code")) for a in answers] == [(409, "stale")]
    assert rot.carried == ["target 90"]


def test_a_nudge_whose_command_before_never_shows_is_refused_as_the_judge_says(
    near: tuple[NearRotator, ConsoleClient], monkeypatch: pytest.MonkeyPatch
) -> None:
    rot, client = near
    monkeypatch.setattr(server, "SHOWN_S", 0.05)
    rot.way.set()
    answer = client.command("near", command="nudge", d_az=5)
    assert (answer.status, answer.doc.get("code")) == (409, "stale")
    assert answer.doc["error"] == ON_ITS_WAY_MESSAGE
    assert rot.carried == []


def test_a_nudge_beyond_the_waiters_bound_is_refused_at_once_and_the_waiting_one_still_goes(
    near: tuple[NearRotator, ConsoleClient], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each waiting nudge looks every SHOWN_POLL_S: a client posting hundreds at a line that
    owes a long reply kept the loop busy with their looks. Beyond SHOWN_WAITERS, one is
    refused at once, said as busy; the one waiting is judged as before."""
    rot, client = near
    monkeypatch.setattr(server, "SHOWN_WAITERS", 1)
    rot.way.set()
    answers: list[Answer] = []
    first = _posted(client, answers, command="nudge", d_az=5, page="p", seq=2)
    _waiting(rot)
    second = client.command("near", command="nudge", d_az=5, page="p", seq=3)
    assert (second.status, second.doc.get("code")) == (409, "busy")
    assert "1 commands already wait for this rotator" in second.doc["error"]
    rot.way.clear()
    first.join(slow(10))
    assert [a.status for a in answers] == [200]
    assert rot.carried == ["nudge +5"]
