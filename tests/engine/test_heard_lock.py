"""kept.py rule 10: only a state file's lock ON is the last word on the lock at a start. The
``R/lock/state`` ON the broker held from an earlier run (the first look hands it on:
interfaces/mqtt/look.py rule 14) locks a rotator whose file does not say ON (nothing, or OFF:
attack 15), saved and said; a file that says ON, or a lock word since the start, is newer and
wins."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pytest

from bridge.core.errors import Refused
from bridge.core.model import ErrorEvent, ErrorKind, Target
from bridge.runtime.rotator import (
    HEARD_LOCK_MESSAGE,
    HEARD_OVER_OFF_MESSAGE,
    OFFLINE_MESSAGE,
    UNHEARD_LOCK_MESSAGE,
    UNREAD_LOCK_MESSAGE,
)
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


def test_a_lock_on_the_broker_held_locks_a_rotator_whose_state_file_says_off(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Attack 15: the file's OFF cannot tell the broker's ON older or newer (the ON was set on a
    run of the bridge by hand, on another state file; or the OFF was saved while the broker was
    away and never reached it): it used to win, and the ON was put back as OFF without a word.
    A lock is safety state: the ON locks it, said as the file's OFF overridden."""
    st, events = _with_file(tmp_path, {"locked": False})
    assert st.rot.heard_lock(b"ON")
    shown = st.settle()
    assert st.rot.locked and shown.locked
    assert StateStore(st.path).locked("tower")
    assert [(e.kind, e.message) for e in events] == [(ErrorKind.STATE, HEARD_OVER_OFF_MESSAGE)]
    assert "state file says OFF" in HEARD_OVER_OFF_MESSAGE
    assert "lock OFF releases it" in HEARD_OVER_OFF_MESSAGE
    assert f"tower: {HEARD_OVER_OFF_MESSAGE}" in caplog.messages
    with pytest.raises(Refused, match="locked"):
        st.rot.submit(Target(100.0, None))
    assert st.restarted().locked


def test_a_state_file_that_says_the_lock_on_wins(tmp_path: Path) -> None:
    """An ON kept is the last word: the broker's OFF (or none) is older, a stranger's, or an OFF
    said on another run's file; kept locked, the safe side. (Until attack 15 a file's OFF won
    the same way: now it does not, above.)"""
    st, events = _with_file(tmp_path, {"locked": True})
    for payload in (b"OFF", None):
        assert not st.rot.heard_lock(payload)
    assert st.rot.locked and events == []


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


@pytest.mark.parametrize(
    "entry",
    [None, {"options": {}}, {"locked": False}],
    ids=["no file", "no lock", "file says OFF"],
)
def test_no_motion_until_the_broker_said_a_lock_the_state_file_does_not_say(
    tmp_path: Path, entry: dict[str, object] | None
) -> None:
    """Before the first look (the broker down, or slower to start than the bridge) a target
    from rotctld, the console or a logger turned a rotor whose lock only the broker still
    held; it is refused until the look hands on what the broker held (nothing: free). A file
    that says OFF waits too (attack 15: it used to wait for no broker, and the ON the broker
    held from a run on another state file was lost)."""
    st, _ = _with_file(tmp_path, entry)
    st.rot.await_heard_lock()
    with pytest.raises(Refused, match="R/lock/state") as refused:
        st.rot.submit(Target(100.0, None))
    assert refused.value.message == UNHEARD_LOCK_MESSAGE
    assert not st.rot.heard_lock(None)
    assert _judged(st) == OFFLINE_MESSAGE  # (the judge goes on: this station has no link)


def test_a_state_file_that_says_the_lock_on_waits_for_no_broker(tmp_path: Path) -> None:
    """Locked at once, and said so (not "not known yet"). A file that says OFF waits now
    (attack 15: above)."""
    st, _ = _with_file(tmp_path, {"locked": True})
    st.rot.await_heard_lock()
    assert "locked (safety lock ON)" in _judged(st)
    assert not st.settle().lock_unknown


def test_a_rotator_that_is_never_told_to_wait_never_waits(tmp_path: Path) -> None:
    """Only the bridge (app.py, which always has a broker to ask) calls ``await_heard_lock``;
    a file that says OFF, or nothing, refuses no motion for the lock without it."""
    for name, entry in (("new", None), ("off", {"locked": False})):
        (tmp_path / name).mkdir()
        st, _ = _with_file(tmp_path / name, entry)
        assert _judged(st) == OFFLINE_MESSAGE


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


def test_a_wait_for_the_broker_is_said_at_start_and_a_lock_off_that_ends_it_is_said_too(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """kept.py rule 10 (review 62's advice): an operator reading the log learns why motion is
    refused from the start, and that a lock OFF sent before the broker was read may have
    released a lock ON the broker holds."""
    caplog.set_level(logging.INFO, logger="bridge.runtime.rotator")
    st, _ = _with_file(tmp_path, {"locked": False})
    st.rot.await_heard_lock()
    waits = [m for m in caplog.messages if "until the broker's R/lock/state is read" in m]
    assert waits and waits[0].startswith("tower: motion refused")
    console_lock(st.rot, False)
    assert any("before its R/lock/state was read" in m for m in caplog.messages)
    assert _judged(st) == OFFLINE_MESSAGE


def test_a_lock_off_after_the_broker_was_read_is_not_said_as_ending_the_wait(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    st, _ = _with_file(tmp_path, {"locked": False})
    st.rot.await_heard_lock()
    assert not st.rot.heard_lock(None)
    console_lock(st.rot, False)
    assert not any("before its R/lock/state was read" in m for m in caplog.messages)


def test_a_lock_state_the_broker_does_not_let_the_bridge_read_keeps_the_wait(
    tmp_path: Path,
) -> None:
    """Review 62: a broker whose ACL drops what it would send on ``R/lock/state`` showed the
    ON it held as nothing, and the rotator started unlocked. Unread (look.py rule 14's probe
    not back), the rotator waits on, said, until a lock word."""
    st, events = _with_file(tmp_path, {"locked": False})
    st.rot.await_heard_lock()
    assert st.rot.lock_unread()
    assert [(e.kind, e.message) for e in events] == [(ErrorKind.STATE, UNREAD_LOCK_MESSAGE)]
    assert "cannot read R/lock/state (the broker's ACL?)" in UNREAD_LOCK_MESSAGE
    assert _judged(st) == UNHEARD_LOCK_MESSAGE
    assert st.settle().lock_unknown
    assert not st.rot.heard_lock(None)  # (another rotator's late witness: nothing read here)
    assert _judged(st) == UNHEARD_LOCK_MESSAGE
    console_lock(st.rot, True)  # a lock word ends it (ON here: the safe side)
    assert st.rot.locked and not st.rot.lock_waits


def test_a_lock_state_unread_changes_nothing_for_a_rotator_whose_file_says_on(
    tmp_path: Path,
) -> None:
    st, events = _with_file(tmp_path, {"locked": True})
    st.rot.await_heard_lock()
    assert not st.rot.lock_unread()
    assert events == [] and st.rot.locked
