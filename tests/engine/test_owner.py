"""One owner per rotator for its safety state (kept.py rule 5, operators.py rule 1): a lock
word or a change of the control lease is decided, put in the mailbox and its save queued in
one step, whichever interfaces race. Each test forces the interleaving a review found: the
first word is held between its steps (inside its mailbox put) while the other word runs on a
thread of its own until it returns or has to wait its turn at the owner; then the first goes on.
No timing decides it. Then the judge, the session (what ``R/lock/state`` and ``R/control``
publish), the state file and a rotator built from that file after a restart must agree.
"""

from __future__ import annotations

import logging
import os
import threading
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bridge.app import worker_config
from bridge.core.model import Control, Origin, RotatorStatus, Source
from bridge.interfaces.mqtt.halts import Halts
from bridge.interfaces.mqtt.topics import Topics
from bridge.interfaces.web.commands import WebCommand, carry_out
from bridge.runtime.kept import Owner
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.session.mailbox import Mailbox
from bridge.settings import RotatorSettings
from tests.support.waiting import slow

T0 = 1_790_000_000.0
HOLDER = Origin(Source.MQTT, "DL1ABC")
OTHER = Origin(Source.MQTT, "G4XYZ")


class Clock:
    def __init__(self) -> None:
        self.now = T0

    def __call__(self) -> float:
        return self.now


class Turns(deque[threading.Lock]):
    """The owner's steps waiting their turn (kept.py ``Owner``), saying when one has to."""

    def __init__(self) -> None:
        super().__init__()
        self.waiting = threading.Event()
        self.came = threading.Semaphore(0)  # one for each step that had to wait

    def append(self, turn: threading.Lock) -> None:
        super().append(turn)
        self.waiting.set()
        self.came.release()


class Station:
    """One rotator, its state file, what its session published, and its stop lane."""

    def __init__(self, tmp_path: Path, clock: Clock | None = None) -> None:
        self.path = tmp_path / "state.json"
        self.clock = clock or Clock()
        self.cfg = worker_config(RotatorSettings(id="tower", model="rotorez", port="/dev/null"))
        self.store = StateStore(self.path)
        self.statuses: list[RotatorStatus] = []
        self.rot = Rotator(
            self.cfg, self.store, self.statuses.append, lambda e: None, wall=self.clock
        )
        worker = self.rot._worker
        worker._do(worker.session.start(0.0))  # the first status, as the lines thread's
        self.threads: list[threading.Thread] = []

    def lane(self) -> Halts:
        """The MQTT stop lane while the main connection is down: its word is the only one."""

        class Down:
            up = hears = False

            def publish_marker(self, topic: str, payload: str) -> None:
                raise AssertionError("no marker while the main connection is down")

        topics = Topics("rotor", {"tower": "rotor/tower"})
        rotators = {"tower": self.rot}
        up = Down()
        return Halts(topics, up, rotators, self.clock, retain_is_live=True, on_problem=None)

    def in_between(self, step: Callable[[], None], turns: Turns) -> None:
        """``step`` on a thread of its own, until it returns or waits for its turn."""
        returned_or_waiting = turns.waiting

        def run() -> None:
            step()
            returned_or_waiting.set()

        thread = threading.Thread(target=run, daemon=True)
        self.threads.append(thread)
        thread.start()
        assert returned_or_waiting.wait(slow(10)), "the other word neither returned nor waited"

    def hold_between_steps(self, put: str, when: object, other: Callable[[], None]) -> None:
        """The first call of the mailbox's ``put`` with ``when`` runs ``other`` in between."""
        turns = Turns()
        owner = getattr(self.rot, "_owner", None)  # before the owner no step had to wait
        if owner is not None:
            owner._waiting = turns
        mailbox = self.rot._mailbox
        real = getattr(mailbox, put)
        once = [True]

        def held(value: object, **kw: object) -> None:
            if value == when and once[0]:
                once[0] = False
                self.in_between(other, turns)
            real(value, **kw)

        setattr(mailbox, put, held)

    def settle(self) -> RotatorStatus:
        """Every thread done, the session served the mailbox, the writer wrote: the status the
        session published last (what R/lock/state and R/control say)."""
        for thread in self.threads:
            thread.join(slow(10))
            assert not thread.is_alive()
        self.store.flush()  # (the writer says what it saved to the session: kept.py rule 2)
        self.rot._worker.serve(0.0, {self.rot._mailbox.fileno()})
        self.store.flush()  # (what the session's step handed the writer: a stop owed)
        return self.statuses[-1]

    def restarted(self) -> Rotator:
        store = StateStore(self.path)
        return Rotator(self.cfg, store, lambda s: None, lambda e: None, wall=self.clock)


def console_lock(rot: Rotator, on: bool) -> None:
    carry_out(rot, WebCommand("lock", on=on), "192.168.1.20")


@pytest.mark.parametrize("held_first", ["lane lock ON", "console lock OFF"])
def test_a_console_lock_off_racing_a_stop_lane_lock_on(tmp_path: Path, held_first: str) -> None:
    """Either word held between its steps while the other runs: the judge, the session, the
    state file and the restart agree on one lock (before the owner: the judge unlocked, the
    session and R/lock/state locked, the file unlocked; or the other way round)."""
    st = Station(tmp_path)
    lane = st.lane()

    def lane_on() -> None:
        lane.on_lane("rotor/tower/lock", b"ON", False, Origin(Source.MQTT))

    def console_off() -> None:
        console_lock(st.rot, False)

    if held_first == "lane lock ON":
        st.hold_between_steps("put_lock", True, console_off)
        lane_on()
    else:
        st.hold_between_steps("put_lock", False, lane_on)
        console_off()
    shown = st.settle()
    saved = StateStore(st.path).locked("tower")
    last_word = held_first == "console lock OFF"  # the word that waited came last
    assert (st.rot.locked, shown.locked, saved) == (last_word,) * 3
    again = st.restarted()
    assert again.locked is shown.locked  # what R/lock/state said last
    assert again._worker.session.status.locked is shown.locked


@pytest.mark.parametrize("held_first", ["claim", "release", "end"])
def test_the_lease_changed_by_two_at_once(tmp_path: Path, held_first: str) -> None:
    """A claim held between its decision and its put while another releases it; a release, or
    the lease's end, held while another claims: the judge, R/control and the state file name
    one holder, and so does the restart (before the owner: the judge free while R/control and
    the file named a holder who blocked everyone after a restart, or the other way round)."""
    st = Station(tmp_path)
    ops = st.rot.operators
    if held_first == "claim":
        st.hold_between_steps(
            "put_control",
            Control("DL1ABC", T0 + 1800),
            lambda: ops.release(OTHER),
        )
        ops.claim("DL1ABC", 30, HOLDER)
        expected = None
    else:
        ops.claim("DL1ABC", 30, HOLDER)

        def other_claims() -> None:
            ops.claim("G4XYZ", 30, OTHER)

        st.hold_between_steps("put_control", None, other_claims)
        if held_first == "release":
            ops.release(HOLDER)
        else:
            st.clock.now += 1800  # its end, as the timer says it
            ops._expire()
        expected = Control("G4XYZ", st.clock.now + 1800)
    shown = st.settle()
    ops.stop()
    saved = StateStore(st.path).lease("tower")
    assert (ops.holder, shown.control, saved) == (expected,) * 3
    again = st.restarted()
    assert again.operators.holder == shown.control  # what R/control said last


def test_a_lock_kept_from_the_state_file_is_said_at_start(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    st = Station(tmp_path)
    console_lock(st.rot, True)
    st.settle()
    with caplog.at_level(logging.INFO, logger="bridge"):
        again = st.restarted()
    assert again.locked
    assert "tower: safety lock ON, kept from the state file" in caplog.messages
    caplog.clear()
    console_lock(again, False)
    again._store.flush()
    with caplog.at_level(logging.INFO, logger="bridge"):
        st.restarted()
    assert not any("safety lock" in m for m in caplog.messages)  # unlocked: nothing to say


def test_the_step_writes_no_byte_and_starts_no_thread_while_it_holds_the_lock(
    tmp_path: Path,
) -> None:
    """kept.py rule 5: a lock ON waiting for another word's step waits for no system call and
    no thread start (each can give the GIL away for milliseconds): the wake byte for the lines
    thread and the state writer come once the step has let go."""
    st = Station(tmp_path)
    mailbox, writer = st.rot._mailbox, st.store._writer
    assert writer._thread is None  # nothing saved yet: no writer (ondemand.py rule 3)
    seen: list[tuple[bool, bool]] = []
    real = mailbox.put_lock

    def put_lock(locked: bool, **kw: object) -> None:
        real(locked, **kw)
        seen.append((woken(), writer._thread is not None))

    def woken() -> bool:
        try:
            return bool(os.read(mailbox.fileno(), 4096))
        except BlockingIOError:
            return False

    mailbox.put_lock = put_lock  # type: ignore[method-assign]
    console_lock(st.rot, False)
    assert seen == [(False, False)]  # in the step: nothing
    assert woken() and writer._thread is not None  # after it: both
    st.store.flush()
    assert StateStore(st.path).locked("tower") is False


def test_the_steps_take_turns_in_the_order_they_came() -> None:
    """A lock ON that waits for a step waits only for the steps that came before it: a flood
    of words that come after it cannot take the turn first (a plain lock lets the thread that
    let go take it again for as long as it keeps the GIL)."""
    mailbox = Mailbox()
    owner = Owner(StateStore(None), mailbox)
    owner._waiting = turns = Turns()
    done: list[str] = []

    def step(name: str) -> threading.Thread:
        def run() -> None:
            with owner:
                done.append(name)

        thread = threading.Thread(target=run, daemon=True)
        thread.start()
        assert turns.came.acquire(timeout=slow(10)), f"{name} did not wait its turn"
        return thread

    owner.__enter__()  # a step under way
    threads = [step("lock ON"), step("lock OFF"), step("claim")]
    owner.__exit__(None, None, None)
    for thread in threads:
        thread.join(slow(10))
    assert done == ["lock ON", "lock OFF", "claim"]
    with owner:  # free again
        done.append("release")
    assert done[-1] == "release" and not turns
    mailbox.close()


def test_a_lane_lock_on_starts_no_thread_and_writes_no_byte_under_the_word_lock(
    tmp_path: Path,
) -> None:
    """kept.py rule 5 under halts.py's lock: the owner let go of its step and woke the lines
    thread and started the state writer at once, while the stop lane's word lock was still
    held, so a lane STOP behind a lane lock ON waited for a thread start. Both come once the
    word lock has let go."""
    st = Station(tmp_path)
    lane = st.lane()
    mailbox, writer = st.rot._mailbox, st.store._writer
    assert writer._thread is None  # nothing saved yet: no writer (ondemand.py rule 3)
    seen: list[tuple[str, bool]] = []  # each wake, and whether the word lock was held

    def watched(name: str, real: Callable[[], None]) -> Callable[[], None]:
        def call() -> None:
            seen.append((name, lane._lock.locked()))
            real()

        return call

    mailbox.wake_once = watched("lines", mailbox.wake_once)  # type: ignore[method-assign]
    st.store.wake = watched("writer", st.store.wake)  # type: ignore[method-assign]
    lane.on_lane("rotor/tower/lock", b"ON", False, Origin(Source.MQTT))
    assert seen == [("lines", False), ("writer", False)]
    assert writer._thread is not None  # the save's writer, started after the word lock
    assert os.read(mailbox.fileno(), 4096)  # and the lines thread woken
    st.store.flush()
    assert StateStore(st.path).locked("tower") is True


@pytest.mark.parametrize("word", [True, False])
def test_the_lock_is_said_only_once_the_state_file_holds_it(tmp_path: Path, word: bool) -> None:
    """kept.py rule 2: a lock ON is in effect at once (the judge) and said (the status:
    ``R/lock/state``, ``R/status``) once the writer has saved it: every status that shows the
    lock finds it in the state file, so a crash right after the bridge said lock ON restarts
    it locked (an attack pass: the bridge killed the moment R/lock/state said ON came back
    unlocked in 4 of 6 rounds, and a target turned the rotor). A lock OFF is said at once
    (never locked shown while a target turns the rotor); its save follows."""
    if not word:  # (a lock OFF: from a lock the file kept)
        kept = StateStore(tmp_path / "state.json")
        kept.set_locked("tower", True)
        kept.flush()
    st = Station(tmp_path)
    assert st.statuses[-1].locked is not word
    busy, go = threading.Event(), threading.Event()

    def writer_busy() -> None:  # the writer on an earlier save, a slow SD card
        busy.set()
        go.wait(slow(10))

    st.store.later(writer_busy)
    assert busy.wait(slow(10))
    console_lock(st.rot, word)
    st.rot._worker.serve(0.0, {st.rot._mailbox.fileno()})
    assert st.rot.locked is word  # in effect: the judge refuses motion (or takes it) now
    assert st.statuses[-1].locked is False  # ON not said: the file does not hold it yet
    assert StateStore(st.path).locked("tower") is not word
    go.set()
    shown = st.settle()
    assert shown.locked is word and StateStore(st.path).locked("tower") is word


@pytest.mark.parametrize("first", ["kept ON", "ON being saved"])
def test_a_lock_on_after_an_off_is_not_said_while_the_off_is_saved(
    tmp_path: Path, first: str
) -> None:
    """review 93, kept.py rule 2: ON, OFF, ON. The second ON was said at once: the session
    still had the first ON as the lock saved last (kept from the file, or said by its save
    that ended after the OFF), while the writer was writing the OFF. The file held OFF while
    ``R/lock/state`` said ON: a crash then restarted the bridge unlocked although it said
    lock ON (what rule 2 is there to prevent)."""
    if first == "kept ON":
        kept = StateStore(tmp_path / "state.json")
        kept.set_locked("tower", True)
        kept.flush()
    st = Station(tmp_path)
    serve = lambda: st.rot._worker.serve(0.0, {st.rot._mailbox.fileno()})  # noqa: E731
    real = st.store.set_locked
    wrote: dict[bool, threading.Event] = {True: threading.Event(), False: threading.Event()}
    go: dict[bool, threading.Event] = {True: threading.Event(), False: threading.Event()}

    def slow_save(rid: str, locked: bool, *places: Any) -> bool:  # the write done, its word
        saved = real(rid, locked, *places)  # not yet said
        wrote[locked].set()
        go[locked].wait(slow(10))
        return saved

    st.store.set_locked = slow_save  # type: ignore[method-assign]
    if first == "ON being saved":
        console_lock(st.rot, True)
        serve()
        assert wrote[True].wait(slow(10))
    else:
        go[True].set()
    console_lock(st.rot, False)
    serve()
    assert st.statuses[-1].locked is False
    go[True].set()  # (the first ON's save, if any, says itself now)
    assert wrote[False].wait(slow(10))  # the OFF is in the file; its save not said yet
    assert StateStore(st.path).locked("tower") is False
    serve()
    console_lock(st.rot, True)
    serve()
    assert st.rot.locked is True
    shown = st.statuses[-1].locked
    on_file = StateStore(st.path).locked("tower")
    assert not (shown and not on_file), "lock ON said while the state file holds OFF"
    go[False].set()
    final = st.settle()
    assert final.locked is True and StateStore(st.path).locked("tower") is True
