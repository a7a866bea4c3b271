from __future__ import annotations

import errno
import json
import logging
import os
import threading
import time
from pathlib import Path

import pytest

from bridge.app import App
from bridge.runtime.state_store import InUse, StateStore, boot_clock, held, tilde_leftover
from bridge.settings import Settings
from tests.support.waiting import slow


def test_lock_and_options_survive_a_restart(tmp_path: Path) -> None:
    path = tmp_path / "sub" / "state.json"
    s = StateStore(path)
    assert s.locked("tower") is False and s.options("tower") == {}
    s.set_locked("tower", True)
    s.set_option("tower", "jam", False)
    again = StateStore(path)
    assert again.locked("tower") is True and again.options("tower") == {"jam": False}
    assert again.locked("other") is False
    assert json.loads(path.read_text())["rotators"]["tower"]["locked"] is True


def test_a_stop_owed_survives_a_restart_and_a_damaged_one_is_owed(tmp_path: Path) -> None:
    """kept.py rule 8: a stop owed is kept until it is owed no more; a value that is not
    false (a hand-edited file) is owed: one stop more is the safe side."""
    path = tmp_path / "state.json"
    s = StateStore(path)
    assert s.stop_owed("tower") is False
    assert s.set_stop_owed("tower", True) is True
    assert StateStore(path).stop_owed("tower") is True
    assert s.set_stop_owed("tower", False) is True
    assert "stop_owed" not in json.loads(path.read_text())["rotators"]["tower"]
    assert StateStore(path).stop_owed("tower") is False
    path.write_text('{"rotators": {"tower": {"stop_owed": "yes"}}}')
    assert StateStore(path).stop_owed("tower") is True


def test_the_target_a_rotor_rests_short_of_survives_a_restart(tmp_path: Path) -> None:
    """kept.py rule 9; a damaged value is none (a guard the less, never a move)."""
    path = tmp_path / "state.json"
    s = StateStore(path)
    assert s.short_of("tower") is None
    assert s.set_short_of("tower", 300.0) is True
    assert StateStore(path).short_of("tower") == 300.0
    assert s.set_short_of("tower", None) is True
    assert "short_of" not in json.loads(path.read_text())["rotators"]["tower"]
    for damaged in ('"300"', "true", "1e999", "[300]"):
        path.write_text('{"rotators": {"tower": {"short_of": ' + damaged + "}}}")
        assert StateStore(path).short_of("tower") is None


def test_the_controllers_version_survives_a_restart_for_its_model_alone(tmp_path: Path) -> None:
    """state_store.py rule 12: kept with the model's name; another model's (the controller
    swapped), or a damaged one, is none."""
    path = tmp_path / "state.json"
    s = StateStore(path)
    assert s.version("tower", "rotorez") is None
    assert s.set_version("tower", "rotorez", "1.4S") is True
    assert StateStore(path).version("tower", "rotorez") == "1.4S"
    assert StateStore(path).version("tower", "rotorcard") is None
    pair = "V" * 78 + " / " + "W" * 78  # (two boxes' versions joined, each a whole line's)
    assert s.set_version("sky", "easycomm3-az+easycomm3", pair) is True
    assert StateStore(path).version("sky", "easycomm3-az+easycomm3") == pair
    assert StateStore(path).locked("tower") is False  # (no lock said: kept.py rule 10 holds)
    assert StateStore(path).holds_lock("tower") is False
    for damaged in (
        '"1.4S"',
        '{"model": "rotorez"}',
        '{"model": "rotorez", "text": 14}',
        '{"model": "rotorez", "text": "1.4S\\u001b[2J"}',
        '{"model": "rotorez", "text": "' + "9" * 256 + '"}',
    ):
        path.write_text('{"rotators": {"tower": {"version": ' + damaged + "}}}")
        assert StateStore(path).version("tower", "rotorez") is None, damaged
        assert StateStore(path).problems == {}


def test_a_state_file_behind_a_link_is_written_through_it(tmp_path: Path) -> None:
    """Rule 4, an attack pass: the first save replaced the link with a file of its own, and
    the file it pointed to (on another volume, say) was never read again."""
    real = tmp_path / "data" / "state.json"
    real.parent.mkdir()
    StateStore(real).set_locked("tower", True)
    link = tmp_path / "state.json"
    link.symlink_to(real)
    s = StateStore(link, deferred=True)
    assert s.locked("tower") is True
    s.check_writable()
    assert s.set_locked("yagi", True) is True
    assert link.is_symlink()
    assert StateStore(real).locked("yagi") is True and StateStore(real).locked("tower") is True


def test_the_installations_lock_follows_the_file_a_link_names(tmp_path: Path) -> None:
    """Rule 7, a review: held by the link's name, the lock let a second installation naming
    the same file by its real path start too."""
    real = tmp_path / "data" / "state.json"
    real.parent.mkdir()
    StateStore(real).set_locked("tower", False)
    link = tmp_path / "state.json"
    link.symlink_to(real)
    with held(link), pytest.raises(InUse):
        with held(real):
            pass


def test_a_link_where_the_installations_lock_goes_is_refused_and_its_file_left_alone(
    tmp_path: Path,
) -> None:
    """Rule 7, an attack pass: the lock's file is emptied for the holder's process id, and
    opened through a link (``state.json.lock`` naming the audit file) it emptied that file at
    every start."""
    audit = tmp_path / "audit.log"
    audit.write_text("2026-12-02 lock ON by DL1ABC\n")
    (tmp_path / "state.json.lock").symlink_to(audit)
    with pytest.raises(OSError, match=r"state\.json\.lock is a symbolic link"):
        with held(tmp_path / "state.json"):
            pass
    assert audit.read_text() == "2026-12-02 lock ON by DL1ABC\n"


def test_a_state_file_link_that_loops_is_refused_by_its_kind(tmp_path: Path) -> None:
    loop = tmp_path / "state.json"
    loop.symlink_to(loop)
    s = StateStore(loop, deferred=True)
    assert s.corrupt and s.locked("tower") is True
    with pytest.raises(OSError, match="link that cannot be followed"):
        s.check_writable()


def test_an_unreadable_state_file_starts_every_rotator_locked(tmp_path: Path) -> None:
    path = tmp_path / "state.json"
    path.write_text("{not json")
    s = StateStore(path)
    assert s.locked("tower") is True and s.locked("yagi") is True  # safety before convenience
    assert s.set_locked("tower", False) is True  # the user unlocks one explicitly
    again = StateStore(path)
    assert again.locked("tower") is False
    assert again.locked("yagi") is True  # still locked after the restart: nobody unlocked it


def test_an_unreadable_state_file_says_why_each_rotator_starts_locked(tmp_path: Path) -> None:
    """state_store.py rule 2: as for a malformed entry, the rotator's status says why it is
    locked (runtime/rotator.py puts ``problems`` as its last error); an unreadable file was
    said in the log alone, and the status showed a lock nobody had set, with no reason."""
    path = tmp_path / "state.json"
    path.write_text("garbage{")
    s = StateStore(path)
    assert s.locked("tower") is True and s.locked("yagi") is True
    for rid in ("tower", "yagi"):
        assert s.problems[rid].startswith(f"state file {path} unreadable (")
        assert s.problems[rid].endswith("): every rotator starts locked")
    assert StateStore(path).problems == {}  # written down locked: the next start is clean


def test_a_state_file_nested_too_deep_starts_every_rotator_locked(tmp_path: Path) -> None:
    """state_store.py rule 2 for a file of nested brackets (a few kilobytes past the parser's
    depth): the start died of a RecursionError, every 5 s under systemd (an attack pass)."""
    path = tmp_path / "state.json"
    path.write_text('{"rotators": {"tower": {"health": ' + "[" * 5000 + "]" * 5000 + "}}}")
    s = StateStore(path)
    assert s.corrupt and s.locked("tower") is True


def test_a_lock_that_cannot_be_saved_says_so(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    s = StateStore(blocker / "state.json")  # its directory cannot be created
    assert s.set_locked("tower", True) is False


@pytest.mark.parametrize(
    "entry",
    [
        "x",
        None,
        [],
        5,
        {"locked": "yes"},
        {"locked": 1},
        {"options": "x"},
        {"options": {"jam": None}},  # (a text is a choice's name: kept.py reads it by model)
        {"options": {"jam": [True]}},
    ],
)
def test_a_malformed_entry_starts_its_rotator_locked_and_says_why(
    tmp_path: Path, entry: object
) -> None:
    """Issue 14, item 7: {"rotators": {"tower": "x"}} was a traceback and exit 1 at start-up,
    restarted by systemd every 5 s forever."""
    path = tmp_path / "state.json"
    good = {"locked": False, "options": {"jam": True}}
    path.write_text(json.dumps({"rotators": {"tower": entry, "yagi": good}}))
    s = StateStore(path)
    assert s.locked("tower") is True and s.options("tower") == {}
    assert "entry for 'tower' is malformed" in s.problems["tower"]
    assert s.locked("yagi") is False and s.options("yagi") == {"jam": True}  # the others as set
    assert json.loads(path.read_text())["rotators"]["tower"] == {"locked": True}  # kept locked
    assert StateStore(path).problems == {}  # written down properly: the next start is clean


def test_a_malformed_lease_is_said_cut_short(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Attack 18's rule for what a file holds (a quotation cut short, as a malformed entry's
    at 80 characters): a lease of a megabyte was one megabyte line in the log."""
    path = tmp_path / "state.json"
    path.write_text(json.dumps({"rotators": {"tower": {"lease": "L" * 1_000_000}}}))
    with caplog.at_level(logging.WARNING, logger="bridge.runtime.state_store"):
        assert StateStore(path).lease("tower") is None
    said = [r.getMessage() for r in caplog.records]
    assert said == [f"state file: lease for 'tower' is malformed (\"{'L' * 79}): ignored"], said


def test_the_start_writes_the_real_content_but_never_over_an_unreadable_file(
    tmp_path: Path,
) -> None:
    path = tmp_path / "state.json"
    StateStore(path).check_writable()
    assert json.loads(path.read_text()) == {"rotators": {}}  # the file as every change writes it
    StateStore(path).set_locked("tower", True)
    StateStore(path).check_writable()
    assert json.loads(path.read_text())["rotators"]["tower"]["locked"] is True  # kept as it was
    path.write_text("{not json")
    StateStore(path).check_writable()  # the directory takes a file; the one there stays
    assert path.read_text() == "{not json"
    assert [p.name for p in tmp_path.iterdir()] == ["state.json"]
    assert StateStore(path).locked("tower") is True  # (written down locked: kept aside first)
    assert (tmp_path / "state.json.unreadable").read_text() == "{not json"


def test_a_write_that_fails_keeps_the_old_file_and_leaves_no_temporary_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "state.json"
    s = StateStore(path)
    s.set_locked("tower", True)

    def disk_gone(fd: int) -> None:
        raise OSError(errno.EIO, "Input/output error")

    monkeypatch.setattr(os, "fsync", disk_gone)
    assert s.set_locked("tower", False) is False
    with pytest.raises(OSError, match="Input/output error"):
        s.check_writable()
    assert [p.name for p in tmp_path.iterdir()] == ["state.json"]
    monkeypatch.undo()
    assert StateStore(path).locked("tower") is True


def test_a_settings_value_survives_a_restart_and_one_its_model_refuses_is_left_out(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A GS-232's speed is kept as its name; read back by the model's declaration, a value it
    does not take (hand-edited, or another model's) is logged and never sent."""
    from bridge.protocols import REGISTRY
    from bridge.runtime.kept import Kept

    path = tmp_path / "state.json"
    StateStore(path).set_option("tower", "speed", "2")
    kept = Kept(StateStore(path), "tower", REGISTRY["gs232b"], report=lambda *a: None)
    assert kept.options() == {"speed": "2"}
    for bad in ("9", True, 2):
        path.write_text(json.dumps({"rotators": {"tower": {"options": {"speed": bad}}}}))
        kept = Kept(StateStore(path), "tower", REGISTRY["gs232b"], report=lambda *a: None)
        assert kept.options() == {}
    assert "stored option 'speed' ignored" in caplog.text


def test_a_flood_of_settings_costs_the_card_a_write_or_two_and_a_lock_after_it_is_kept_at_once(
    tmp_path: Path,
) -> None:
    """Anyone who may publish R/option/speed can send thousands a second: each was a whole
    rewrite of the state file with two fsyncs, in line before a lock ON said after them (3000
    words held the lock's save back two minutes at an SD card's 40 ms a write, and wore the
    card). Settings waiting for the writer are saved together, the last value of each; the
    lock is written right behind them."""
    from bridge.protocols import REGISTRY
    from bridge.runtime.kept import Kept

    path = tmp_path / "state.json"
    store = StateStore(path)
    writes: list[dict[str, object]] = []
    save = store._save

    def counted() -> bool:
        writes.append(json.loads(json.dumps(store._data)))
        return save()

    store._save = counted  # type: ignore[method-assign]
    kept = Kept(store, "tower", REGISTRY["gs232b"], report=lambda *a: None)
    for i in range(3000):  # the owner's steps, as rotator.py takes them; the writer not woken
        kept.save_option("speed", "1" if i % 2 else "4")
    kept.set_lock(True)
    store.wake()
    store.flush()
    assert len(writes) <= 2, len(writes)
    assert writes[-1] == {"tower": {"options": {"speed": "1"}, "locked": True}}
    assert StateStore(path).locked("tower") is True
    assert StateStore(path).options("tower") == {"speed": "1"}


def test_a_flood_of_lock_words_costs_the_card_a_write_or_two_and_the_last_word_is_kept(
    tmp_path: Path,
) -> None:
    """A lock ON is never refused, so anyone allowed to lock can send thousands a second:
    each was a rewrite of the state file with its fsyncs. The words waiting for the writer are
    saved as one, the last word's."""
    from bridge.protocols import REGISTRY
    from bridge.runtime.kept import Kept

    path = tmp_path / "state.json"
    store = StateStore(path)
    writes: list[object] = []
    save = store._save

    def counted() -> bool:
        writes.append(json.loads(json.dumps(store._data)))
        return save()

    store._save = counted  # type: ignore[method-assign]
    kept = Kept(store, "tower", REGISTRY["gs232b"], report=lambda *a: None)
    for i in range(3001):  # the owner's steps; the writer not woken
        kept.set_lock(i % 2 == 0)
    store.wake()
    store.flush()
    assert len(writes) <= 2, len(writes)
    assert writes[-1] == {"tower": {"locked": True}}
    assert StateStore(path).locked("tower") is True


@pytest.mark.parametrize(
    "entry",
    [
        '{"locked": true, "locked": false}',
        '{"locked": false, "options": {"jam": true, "jam": false}}',
    ],
)
def test_a_key_given_twice_with_two_values_is_read_as_neither(tmp_path: Path, entry: str) -> None:
    """state_store.py rule 2: json keeps the last value of a key given twice; a hand-edited
    ``"locked": true, "locked": false`` started the rotator unlocked. Now its entry is
    malformed: that rotator alone starts locked, and says why."""
    path = tmp_path / "state.json"
    path.write_text(f'{{"rotators": {{"tower": {entry}, "yagi": {{"locked": false}}}}}}')
    s = StateStore(path)
    assert s.locked("tower") is True and "entry for 'tower' is malformed" in s.problems["tower"]
    assert s.locked("yagi") is False and "yagi" not in s.problems


def test_the_same_value_twice_is_one_value(tmp_path: Path) -> None:
    path = tmp_path / "state.json"
    path.write_text('{"rotators": {"tower": {"locked": false, "locked": false}}}')
    s = StateStore(path)
    assert s.locked("tower") is False and s.problems == {}


def test_a_write_a_killed_process_left_is_removed_at_the_next_start(tmp_path: Path) -> None:
    """state_store.py rule 1: a bridge killed between the temporary file and its rename (the
    OOM killer, a power cut) left it beside the state file, one more at every such crash, for
    ever. The next start, holding the installation's lock, removes its own file's; another
    state file's in the same directory (a second installation) is left alone."""
    path = tmp_path / "state.json"
    StateStore(path).set_locked("tower", True)
    leftover = tmp_path / ".state.json.6b1113d0.tmp"
    leftover.write_text('{"rotators": {"tow')
    others = tmp_path / ".site2.json.abc123.tmp"
    others.write_text("{}")
    with held(path):
        StateStore(path).check_writable()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["state.json", "state.json.lock", others.name]
    )
    assert StateStore(path).locked("tower") is True


def test_what_a_newer_version_keeps_survives_a_save_of_this_one(tmp_path: Path) -> None:
    """state_store.py rule 8: an update rolled back to this version, which saves a lock; the
    newer version started again finds its own tables and keys as it left them."""
    path = tmp_path / "state.json"
    newer = {
        "version": 7,
        "groups": {"stack": {"locked": True}},
        "rotators": {"tower": {"locked": False, "future": [1, 2]}},
    }
    path.write_text(json.dumps(newer))
    s = StateStore(path)
    s.check_writable()
    assert s.set_locked("tower", True)
    kept = json.loads(path.read_text())
    assert kept["version"] == 7 and kept["groups"] == {"stack": {"locked": True}}
    assert kept["rotators"]["tower"] == {"locked": True, "future": [1, 2]}


def test_a_lock_kept_for_a_rotator_no_longer_configured_is_said_at_start(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """state_store.py rule 9: the rotator locked for tower work was renamed in the file
    ('tower' to 'hf'): the renamed one starts unlocked, and the start said nothing of it."""
    path = tmp_path / "state.json"
    path.write_text(json.dumps({"rotators": {"tower": {"locked": True}, "old": {}}}))
    settings = Settings(
        state_file=path,
        rotators=[{"id": "hf", "model": "rotorez", "port": str(tmp_path / "tty")}],
    )
    with caplog.at_level(logging.WARNING, logger="bridge"):
        App(settings)  # built, never started: no broker, no serial port
    said = [m for m in caplog.messages if "keeps the safety lock ON for 'tower'" in m]
    assert len(said) == 1 and "no rotator of the configuration" in said[0]
    assert not any("'old'" in m for m in caplog.messages)  # (not locked: nothing to say)


def test_the_start_leaves_the_writes_of_a_state_file_named_after_its_own_alone(
    tmp_path: Path,
) -> None:
    """state_store.py rule 1: a second installation's state file in the same directory whose
    name begins with this one's (``state.json.site2`` beside ``state.json``) has temporary
    files that began like this one's: this start removed them, a write of that bridge under
    way among them (its rename then failed: a lock ON it said could not be saved)."""
    path = tmp_path / "state.json"
    StateStore(path).set_locked("tower", True)
    theirs = [tmp_path / ".state.json.site2.0a1b2c3d.tmp", tmp_path / ".state.json.x.tmp"]
    for other in theirs:
        other.write_text('{"rotators": {}}')
    with held(path):
        StateStore(path).check_writable()
    assert all(other.exists() for other in theirs)


@pytest.mark.parametrize("digits", [400, 5000])
def test_a_number_too_large_for_a_float_is_left_out_and_the_bridge_still_builds(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, digits: int
) -> None:
    """state_store.py rule 10, an attack pass: an integer of hundreds of digits in the file (a
    damaged or hand-edited one) ended the start in an OverflowError traceback, exit code 1,
    which systemd restarts every 5 s for ever. Now it is a number no setting takes: the
    option is logged and left out, the place the rotor rested short of is none. One of more
    digits than Python's ``int`` reads (4,300) made the whole file unreadable, every rotator
    locked (a review): the same now."""
    huge = "9" * digits  # (as text: Python writes no int of 5,000 digits either)
    path = tmp_path / "state.json"
    entry = f'{{"locked": false, "short_of": {huge}, "options": {{"jam": {huge}}}}}'
    path.write_text(f'{{"rotators": {{"tower": {entry}}}}}')
    settings = Settings(
        state_file=path,
        rotators=[{"id": "tower", "model": "rotorez", "port": str(tmp_path / "tty")}],
    )
    with caplog.at_level(logging.WARNING, logger="bridge"):
        App(settings)  # built, never started: no broker, no serial port
    assert "stored option 'jam' ignored" in caplog.text
    assert StateStore(path).short_of("tower") is None


def test_a_controller_saying_a_new_version_in_every_line_costs_the_card_a_write_or_two(
    tmp_path: Path,
) -> None:
    """kept.py rule 11: an Easycomm III's ``VE...`` is taken whenever it comes, and each new
    one queued a write of the state file with its fsyncs, a lock word's save waiting behind
    them all. The versions waiting for the writer are saved as one, the latest."""
    from bridge.protocols import REGISTRY
    from bridge.runtime.kept import Kept

    path = tmp_path / "state.json"
    store = StateStore(path)
    writes: list[object] = []
    save = store._save

    def counted() -> bool:
        writes.append(json.loads(json.dumps(store._data)))
        return save()

    store._save = counted  # type: ignore[method-assign]
    kept = Kept(store, "tower", REGISTRY["easycomm3"], report=lambda *a: None)
    busy, free = threading.Event(), threading.Event()
    store.later(lambda: (busy.set(), free.wait(slow(10))))  # the writer busy meanwhile
    assert busy.wait(slow(10))
    for i in range(1000):  # the lines thread's statuses, each with another version
        kept.seen_version(f"V{i}")
    free.set()
    store.flush()
    assert len(writes) <= 2, len(writes)
    assert StateStore(path).version("tower", "easycomm3") == "V999"


ADIF = "ADIF export\n<adif_ver:5>3.1.4 <eoh>\n<call:5>G4XYZ <band:3>20m <mode:2>CW <eor>\n"


def test_a_file_that_is_no_state_file_is_kept_aside_before_the_start_writes_the_locks(
    tmp_path: Path,
) -> None:
    """state_store.py rule 2: an attack pass pointed ``state_file`` at an ADIF logbook; the
    start wrote the locks over it, and the logbook was gone."""
    path = tmp_path / "logbook.adi"
    path.write_text(ADIF)
    s = StateStore(path, deferred=True)  # as the bridge builds it
    assert s.locked("tower") is True  # (its lock cannot be read: locked, rule 2)
    s.check_writable()
    assert (tmp_path / "logbook.adi.unreadable").read_text() == ADIF
    assert json.loads(path.read_text())["rotators"]["tower"]["locked"] is True
    assert s.set_locked("tower", False) is True  # the next writes keep nothing aside again
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "logbook.adi",
        "logbook.adi.unreadable",
    ]
    assert StateStore(path).locked("tower") is False


def test_an_unreadable_file_found_again_is_kept_beside_the_first_one_kept(tmp_path: Path) -> None:
    path = tmp_path / "state.json"
    path.write_text(ADIF)
    assert StateStore(path).locked("tower") is True
    path.write_text("{damaged")
    assert StateStore(path).locked("tower") is True
    assert (tmp_path / "state.json.unreadable").read_text() == ADIF
    assert (tmp_path / "state.json.unreadable.2").read_text() == "{damaged"


def test_an_unreadable_file_is_copied_aside_where_no_hard_link_can_be_made(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_links(src: object, dst: object) -> None:
        raise PermissionError(errno.EPERM, "Operation not permitted")

    path = tmp_path / "state.json"
    path.write_text(ADIF)
    s = StateStore(path)
    monkeypatch.setattr(os, "link", no_links)
    assert s.set_locked("tower", False) is True
    assert (tmp_path / "state.json.unreadable").read_text() == ADIF


def test_an_unreadable_file_that_cannot_be_kept_aside_is_not_written_over(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Neither a link nor a copy (a full disk): the lock is not saved, said as any write that
    fails (the rotator stays locked at the next start), and the file stays as it was."""

    def refused(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    path = tmp_path / "state.json"
    path.write_text(ADIF)
    s = StateStore(path)
    monkeypatch.setattr(os, "link", refused)
    real_open = os.open

    def no_new_files(name: object, flags: int, *args: object) -> int:
        if str(name).endswith(".unreadable"):
            refused()
        return real_open(name, flags, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(os, "open", no_new_files)
    assert s.set_locked("tower", False) is False
    assert path.read_text() == ADIF
    assert sorted(p.name for p in tmp_path.iterdir()) == ["state.json"]


def test_a_copy_aside_that_fails_leaves_no_part_of_it_to_take_the_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A cold review: a copy that failed after its file was made (a full disk at the fsync)
    left the part behind, and every later save made another, ``.unreadable`` to ``.5``."""

    def no_links(src: object, dst: object) -> None:
        raise PermissionError(errno.EPERM, "Operation not permitted")

    real_fsync = os.fsync

    def full(fd: int) -> None:
        if os.readlink(f"/proc/self/fd/{fd}").endswith(".unreadable"):
            raise OSError(errno.ENOSPC, "No space left on device")
        real_fsync(fd)

    path = tmp_path / "state.json"
    path.write_text(ADIF)
    s = StateStore(path)
    monkeypatch.setattr(os, "link", no_links)
    monkeypatch.setattr(os, "fsync", full)
    for _ in range(3):
        assert s.set_locked("tower", False) is False
    assert sorted(p.name for p in tmp_path.iterdir()) == ["state.json"]
    assert path.read_text() == ADIF
    monkeypatch.setattr(os, "fsync", real_fsync)  # room again: kept aside, then written
    assert s.set_locked("tower", False) is True
    assert (tmp_path / "state.json.unreadable").read_text() == ADIF


def test_a_tilde_leftover_is_read_only_while_the_home_folders_file_is_not_there(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Rule 13 (review 69): the file an earlier version kept for 'state_file = "~/..."' under
    ./~ of the directory it ran from is read until the home folder's own is written."""
    home, run_from = tmp_path / "home", tmp_path / "cwd"
    old = run_from / "~" / "rb" / "state.json"
    old.parent.mkdir(parents=True)
    old.write_text(json.dumps({"rotators": {"tower": {"locked": True}}}))
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(run_from)
    new = home / "rb" / "state.json"
    assert tilde_leftover(new) == old
    assert tilde_leftover(tmp_path / "elsewhere.json") is None  # not under the home folder
    store = StateStore(new, deferred=True, read_from=tilde_leftover(new))
    assert store.locked("tower")
    store.check_writable()
    assert json.loads(new.read_text())["rotators"]["tower"]["locked"] is True
    assert tilde_leftover(new) is None  # the home folder's own is read from now on


def test_a_turn_kept_survives_a_restart_and_a_damaged_or_unreadable_one_is_kept(
    tmp_path: Path,
) -> None:
    """state_store.py rule 15 (kept.py rule 13): a DCU-1's turn possibly in flight."""
    path = tmp_path / "state.json"
    s = StateStore(path)
    assert s.turn_kept("dcu") is False  # a new file: no turn of any bridge's
    assert s.set_turn_kept("dcu", True) is True
    assert StateStore(path).turn_kept("dcu") is True
    assert StateStore(path).turn_kept("tower") is False  # (another rotator's: none)
    assert s.set_turn_kept("dcu", False) is True
    assert "turn_kept" not in json.loads(path.read_text())["rotators"]["dcu"]
    assert StateStore(path).turn_kept("dcu") is False
    path.write_text('{"rotators": {"dcu": {"turn_kept": "yes"}}}')
    assert StateStore(path).turn_kept("dcu") is True  # damaged: the safe side
    path.write_text("not json")
    assert StateStore(path).turn_kept("dcu") is True  # unreadable: likewise


def test_a_turn_kept_runs_out_on_the_same_boot_only_and_is_kept_on_another_or_unknown(
    tmp_path: Path,
) -> None:
    """state_store.py rule 15 (review 97): a turn kept carries when it runs out, on the
    kernel's boot clock: a start on the same boot past it finds none; before it, on another
    boot, with a boot clock not read, or a damaged end, one kept (the safe side)."""
    path = tmp_path / "state.json"
    clock: list[tuple[str, float] | None] = [("boot-a", 1000.0)]

    def boot() -> tuple[str, float] | None:
        return clock[0]

    s = StateStore(path, boot=boot)
    assert s.set_turn_kept("dcu", True, ("boot-a", 1500.0)) is True
    kept = json.loads(path.read_text())["rotators"]["dcu"]["turn_kept"]
    assert kept == {"boot": "boot-a", "until": 1500.0}
    assert StateStore(path, boot=boot).turn_kept("dcu") is True  # (within its hold)
    clock[0] = ("boot-a", 1500.0)
    assert StateStore(path, boot=boot).turn_kept("dcu") is False  # run out on this boot
    clock[0] = ("boot-b", 5000.0)
    assert StateStore(path, boot=boot).turn_kept("dcu") is True  # another boot: not known
    clock[0] = None
    assert StateStore(path, boot=boot).turn_kept("dcu") is True  # no boot clock: likewise
    clock[0] = ("boot-a", 9000.0)
    assert StateStore(path, boot=boot).turn_kept("dcu") is False
    for damaged in (
        '{"boot": "boot-a"}',
        '{"boot": "", "until": 1.0}',
        '{"boot": "boot-a", "until": "1"}',
        '{"boot": "boot-a", "until": true}',
        '{"boot": "boot-a", "until": 1.0, "more": 1}',
        '{"boot": 7, "until": 1.0}',
        "[]",
        "true",
    ):
        path.write_text(f'{{"rotators": {{"dcu": {{"turn_kept": {damaged}}}}}}}')
        assert StateStore(path, boot=boot).turn_kept("dcu") is True, damaged


def test_the_boot_clock_is_the_kernels_boot_id_and_boottime() -> None:
    """state_store.py rule 15: the clock a turn kept runs out on is this boot's, never set."""
    read = boot_clock()
    assert read is not None
    boot, now = read
    assert boot == Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    assert 0.0 < now <= time.clock_gettime(time.CLOCK_BOOTTIME)
