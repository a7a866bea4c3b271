"""kept.py rule 10: a state file that does not say a rotator's lock is not the last word on it.
The ``R/lock/state`` ON the broker held from an earlier run (the first look hands it on:
interfaces/mqtt/look.py rule 14) locks the rotator, saved and said; a file that says the lock,
either way, or a lock word since the start, is newer and wins."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bridge.core.errors import Refused
from bridge.core.model import ErrorEvent, ErrorKind, Target
from bridge.runtime.rotator import HEARD_LOCK_MESSAGE, OFFLINE_MESSAGE, UNHEARD_LOCK_MESSAGE
from bridge.runtime.state_store import StateStore
from tests.engine.test_owner import Station, console_lock


def _with_file(tmp_path: Path, entry: dict[str, object] | None) -> tuple[Station, list[ErrorEvent]]:
    if entry is not None:
        (tmp_path / "state.json").write_text(json.dumps({"rotators": {"tower": entry}}))
    st = Station(tmp_path)
    events: list[ErrorEvent] = []
    st.rot._on_event = events.append
    return st, events


@pytest.mark.parametrize(
    "entry", [None, {}, {"options": {}}], ids=["no file", "no entry", "no lock"]
)
def test_a_lock_on_the_broker_held_locks_a_rotator_the_state_file_lost(
    tmp_path: Path, entry: dict[str, object] | None
) -> None:
    st, events = _with_file(tmp_path, entry)
    assert st.rot.heard_lock(b"ON")
    shown = st.settle()
    assert st.rot.locked and shown.locked  # the judge, and R/lock/state once saved
    assert StateStore(st.path).locked("tower")  # kept for the next start
    assert [(e.kind, e.message) for e in events] == [(ErrorKind.STATE, HEARD_LOCK_MESSAGE)]
    with pytest.raises(Refused, match="locked"):
        st.rot.submit(Target(100.0, None))  # a target after it is refused
    assert st.restarted().locked


@pytest.mark.parametrize("said", [False, True], ids=["file says OFF", "file says ON"])
def test_a_state_file_that_says_the_lock_wins(tmp_path: Path, said: bool) -> None:
    """An OFF written after the ON the broker holds (or a stranger's ON) is the last word."""
    st, events = _with_file(tmp_path, {"locked": said})
    assert not st.rot.heard_lock(b"ON")
    assert st.rot.locked is said and events == []


def test_a_lock_word_since_the_start_is_newer(tmp_path: Path) -> None:
    """A lock OFF said after the start, before the broker was reached, is not undone."""
    st, events = _with_file(tmp_path, None)
    console_lock(st.rot, False)
    assert not st.rot.heard_lock(b"ON")
    st.settle()
    assert not st.rot.locked and not StateStore(st.path).locked("tower") and events == []


def test_anything_but_on_changes_nothing(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """... and what is neither ON nor OFF is said in the log (an attack pass: a retained
    ``garbage`` there started the rotator unlocked without a word, where the same payload while
    the bridge runs is logged)."""
    st, events = _with_file(tmp_path, None)
    for payload in (b"OFF", b"", b"on", b"ON\x00", b"1", None):
        caplog.clear()
        assert not st.rot.heard_lock(payload)
        said = [r.getMessage() for r in caplog.records if "R/lock/state" in r.getMessage()]
        if payload in (b"OFF", b"", None):
            assert said == []
        else:
            assert said == [
                f"tower: the broker held R/lock/state {payload!r} from before this start, "
                "neither ON nor OFF: not read as a lock; the rotator starts unlocked"
            ]
    st.settle()
    assert not st.rot.locked and events == []


@pytest.mark.parametrize("entry", [None, {"options": {}}], ids=["no file", "no lock"])
def test_no_motion_until_the_broker_said_a_lock_the_state_file_does_not_say(
    tmp_path: Path, entry: dict[str, object] | None
) -> None:
    """Before the first look (the broker down, or slower to start than the bridge) a target
    from rotctld, the console or a logger turned a rotor whose lock only the broker still
    held; it is refused until the look hands on what the broker held (nothing: free)."""
    st, _ = _with_file(tmp_path, entry)
    st.rot.await_heard_lock()
    with pytest.raises(Refused, match="R/lock/state") as refused:
        st.rot.submit(Target(100.0, None))
    assert refused.value.message == UNHEARD_LOCK_MESSAGE
    assert not st.rot.heard_lock(None)
    assert _judged(st) == OFFLINE_MESSAGE  # (the judge goes on: this station has no link)


@pytest.mark.parametrize("said", [False, True], ids=["file says OFF", "file says ON"])
def test_a_state_file_that_says_the_lock_waits_for_no_broker(tmp_path: Path, said: bool) -> None:
    st, _ = _with_file(tmp_path, {"locked": said})
    st.rot.await_heard_lock()
    assert _judged(st) != UNHEARD_LOCK_MESSAGE


def _judged(st: Station) -> str:
    """What the judge says of a target (no link here: at best, that the rotator is offline)."""
    with pytest.raises(Refused) as refused:
        st.rot.submit(Target(100.0, None))
    return refused.value.message


def test_a_lock_word_before_the_broker_is_reached_ends_the_wait(tmp_path: Path) -> None:
    """The operator's lock OFF (the console) is the last word: a target after it is taken."""
    st, _ = _with_file(tmp_path, None)
    st.rot.await_heard_lock()
    console_lock(st.rot, False)
    assert _judged(st) == OFFLINE_MESSAGE
    assert not st.rot.heard_lock(b"ON")
    assert not st.rot.locked
