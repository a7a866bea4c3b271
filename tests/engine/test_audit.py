"""The audit file on a real file system: lines, rotation by size, a full disk (/dev/full gives
ENOSPC on every write), and coming back when the path is writable again."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
from dataclasses import replace
from pathlib import Path

from bridge.core.model import AuditEvent, Origin, Source
from bridge.runtime.audit import (
    FREE_LINES,
    QUEUE_LINES,
    QUIET_S,
    SPAN_S,
    TICK_S,
    AuditFile,
    AuditTrail,
    Runs,
    audit_line,
)
from tests.support.clock import FakeClock
from tests.support.waiting import slow, wait_until


def event(n: int, result: str = "executed") -> AuditEvent:
    origin = Origin(Source.ROTCTLD, None, "192.168.1.20")
    return AuditEvent(1_790_000_000.0 + n, "rotor", origin, f"P {n} 0", result, 90.0)


def lines(path: Path) -> list[dict[str, object]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_every_event_is_one_json_line(tmp_path: Path) -> None:
    audit = AuditFile(tmp_path / "audit.jsonl", 1_000_000)
    audit.start()
    try:
        audit.put(event(1))
        audit.put(event(2, "refused: DL1ABC holds the rotator until 14:43 UTC (25 min left)"))
        audit.flush()
    finally:
        audit.stop()
    first, second = lines(tmp_path / "audit.jsonl")
    assert first == {
        "time": 1_790_000_001.0,
        "rotator": "rotor",
        "operator": "rotctld 192.168.1.20",
        "interface": "rotctld",
        "peer": "192.168.1.20",
        "command": "P 1 0",
        "result": "executed",
        "bearing_before": 90.0,
    }
    assert str(second["result"]).startswith("refused: DL1ABC holds")


def test_the_file_rotates_by_size_and_keeps_a_few(tmp_path: Path) -> None:
    path = tmp_path / "audit.jsonl"
    one = len(json.dumps(event(10).as_dict(), separators=(",", ":"))) + 1
    audit = AuditFile(path, max_bytes=3 * one, keep=2)
    audit.start()
    try:
        for n in range(10, 20):  # ten lines, three to a file
            audit.put(event(n))
        audit.flush()
    finally:
        audit.stop()
    kept = sorted(p.name for p in tmp_path.iterdir())
    assert kept == ["audit.jsonl", "audit.jsonl.1", "audit.jsonl.2"]  # the oldest went
    assert [d["command"] for d in lines(path)] == ["P 19 0"]
    assert [d["command"] for d in lines(tmp_path / "audit.jsonl.1")] == [
        "P 16 0",
        "P 17 0",
        "P 18 0",
    ]
    assert [d["command"] for d in lines(tmp_path / "audit.jsonl.2")][0] == "P 13 0"
    assert all(p.stat().st_size <= 3 * one for p in tmp_path.iterdir())


def test_the_processs_own_output_by_name_gets_every_line_never_rotated() -> None:
    """Review 87 (rule 11): audit_file = /dev/stdout for the journal. Under systemd the
    descriptor is the journal's socket, which no open() of /dev/stdout reaches (ENXIO): the
    lines are written on the descriptor itself, and past max_bytes nothing is renamed."""
    journal, ours = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
    journal.settimeout(slow(5))  # (lines that never come fail the test, not hang it)
    one = len(json.dumps(event(10).as_dict(), separators=(",", ":"))) + 1
    try:
        for name in (f"/dev/fd/{ours.fileno()}", f"/proc/self/fd/{ours.fileno()}"):
            said: list[str | None] = []
            audit = AuditFile(Path(name), max_bytes=2 * one, on_problem=said.append)
            audit.start()
            try:
                for n in range(10, 15):  # more than two files' worth
                    audit.put(event(n))
                audit.flush()
            finally:
                audit.stop()
            got = b""
            while got.count(b"\n") < 5:
                got += journal.recv(65536)
            assert [json.loads(x)["command"] for x in got.splitlines()] == [
                f"P {n} 0" for n in range(10, 15)
            ], name
            assert said == [] and audit.lines_written == 5, said
    finally:
        journal.close()
        ours.close()


def test_a_full_disk_is_reported_once_never_fatal_and_recovers(tmp_path: Path) -> None:
    path = tmp_path / "audit.jsonl"
    os.symlink("/dev/full", path)  # every write: ENOSPC
    said: list[str | None] = []
    audit = AuditFile(path, 1_000_000, on_problem=said.append)
    audit.start()
    try:
        for n in range(3):
            audit.put(event(n))
            audit.flush()
        assert len(said) == 1 and said[0] is not None
        assert "No space left on device" in said[0] and str(path) in said[0]
        assert audit.lines_lost == 3 and audit.lines_written == 0
        path.unlink()  # space again: a plain file at the path
        audit.put(event(7))
        audit.flush()
        assert said[1:] == [None]  # said once that it works again
        assert [d["command"] for d in lines(path)] == ["P 7 0"]
    finally:
        audit.stop()


def test_a_full_queue_drops_and_counts_but_never_blocks(tmp_path: Path) -> None:
    path = tmp_path / "audit.jsonl"
    audit = AuditFile(path, 1_000_000, queue_lines=2)  # not started: nothing drains it
    for n in range(5):
        audit.put(event(n))  # returns at once, whatever the queue holds
    assert audit.lines_lost == 3
    audit.start()
    audit.put(event(9))
    audit.flush()
    audit.stop()
    written = lines(path)
    assert [d["command"] for d in written] == ["P 0 0", "P 1 0", "P 9 0"]
    assert written[0]["dropped"] == 3  # the next line written says how many were left out


def test_whatever_a_sender_wrote_each_event_stays_one_line_of_json(tmp_path: Path) -> None:
    """Text from the wire reaches a line (a refusal quotes a claim's unknown keys): newlines,
    JSON, and the characters str.splitlines and editors also break at (U+0085, U+2028,
    U+2029) are escaped, so any reader sees one JSON object per line."""
    path = tmp_path / "audit.jsonl"
    audit = AuditFile(path, 1_000_000)
    audit.start()
    nasty = 'a\nb\r\x85c\u2028d\u2029e"}\n{"forged": true} Jörg \ud800'
    sent = [
        AuditEvent(1.0, "rotor", Origin(Source.MQTT, "DL1ABC"), nasty, "refused: " + nasty, None),
        event(1),
    ]
    for one in sent:
        audit.put(one)
    audit.flush()
    audit.stop()
    written = lines(path)
    assert len(written) == 2
    assert written[0]["command"] == nasty and written[0]["result"] == "refused: " + nasty
    assert "Jörg" in path.read_text()  # names stay readable, not \\u escapes
    # an attack pass: a lone surrogate (JSON "\\ud800" in a console name or a claim's key)
    # could not be encoded, and the writer's thread died: every later line was lost, unsaid
    assert "\\ud800" in path.read_text()


def test_a_fault_in_writing_costs_its_lines_never_the_writer(tmp_path: Path) -> None:
    """Rule 3: whatever a write raises (not only OSError), its lines are lost and counted,
    and the next are written."""
    path = tmp_path / "audit.jsonl"
    faults = [ValueError("a bug")]

    def write(fd: int, data: bytes) -> int:
        if faults:
            raise faults.pop()
        return os.write(fd, data)

    audit = AuditFile(path, 1_000_000, os_write=write)
    audit.start()
    audit.put(event(0))
    audit.flush()
    audit.put(event(1))
    audit.flush()
    audit.stop()
    written = lines(path)
    assert [d["command"] for d in written] == ["P 1 0"]
    assert written[0]["dropped"] == 1 and audit.lines_lost == 1


def test_an_event_no_line_can_be_made_of_costs_that_line_alone(tmp_path: Path) -> None:
    """Rule 3, a review: a fault in making one line of a batch lost the whole batch, and the
    count of lines lost before it went with it."""
    path = tmp_path / "audit.jsonl"
    audit = AuditFile(path, 1_000_000)
    bad = AuditEvent(1.0, "rotor", Origin(Source.MQTT, "DL1ABC"), object(), "?", None)  # type: ignore[arg-type]
    audit._dropped = 2  # (two left out by a full queue before: said in the next line)
    for one in (event(0), bad, event(2)):
        audit.put(one)
    audit.start()
    audit.flush()
    audit.stop()
    written = lines(path)
    assert [d["command"] for d in written] == ["P 0 0", "P 2 0"]
    assert written[0]["dropped"] == 2 and written[1]["dropped"] == 1


def test_a_stuck_disk_never_holds_up_whoever_hands_in_an_event(tmp_path: Path) -> None:
    """Rule 1, docs/architecture.md rule 12: a front end's thread (paho's, the lines thread
    after a stop) hands events to the trail while the writer hangs on the disk (an NFS mount
    gone, a dying SD card): each hand-in returns, more than the queue holds are dropped and
    counted, R/audit still gets them all (its own limiter decides)."""
    published: list[AuditEvent] = []
    trail = AuditTrail(tmp_path / "audit.jsonl", 1_000_000, lambda _r, e: published.append(e), [])
    assert trail.file is not None
    disk = threading.Event()
    real_append = trail.file._append

    in_writer = threading.Event()

    def stuck(batch: list[str]) -> tuple[int, OSError | None]:
        in_writer.set()
        disk.wait()  # the hang under test, ended by the test itself below
        return real_append(batch)

    trail.file._append = stuck  # type: ignore[method-assign]
    trail.start()
    trail.file.put(event(-1))  # straight to the queue: only the writer handles it
    assert in_writer.wait(slow(60))  # the writer hangs on its first line
    handed_in = threading.Event()
    sent = QUEUE_LINES + 50

    def front_end() -> None:
        audited = trail.of("rotor")
        for n in range(sent):
            audited(event(n))
        handed_in.set()

    worker = threading.Thread(target=front_end, daemon=True)
    worker.start()
    try:
        assert handed_in.wait(slow(60)), "handing in an audit event waited for the disk"
        assert len(published) == sent
    finally:
        disk.set()
        worker.join()
        trail.stop()
    assert trail.file.lines_lost == 50  # the queue ran full: dropped, not waited for...
    assert trail.file.lines_written == 1 + QUEUE_LINES  # ...and the rest written after


def test_a_directory_at_the_path_is_reported_and_left_where_it_is(tmp_path: Path) -> None:
    """Rule 3: ``audit_file`` naming a directory (``/var/log/rotor-bridge`` without the file's
    name) is a write that fails, reported; the directory is not rotated away as if it were
    an old audit file because its size looked big enough."""
    path = tmp_path / "logs"
    path.mkdir()
    (path / "kept.txt").write_text("the user's own file\n")
    said: list[str | None] = []
    audit = AuditFile(path, 100, on_problem=said.append)
    audit.start()
    audit.put(event(1))
    audit.flush()
    audit.stop()
    assert len(said) == 1 and said[0] is not None and str(path) in said[0]
    assert path.is_dir() and (path / "kept.txt").read_text() == "the user's own file\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["logs"]


def test_a_named_pipe_at_the_path_is_reported_never_hangs_the_writer(tmp_path: Path) -> None:
    """Rule 3: ``audit_file`` a FIFO nobody reads (made there by a neighbour, or left by a
    tool): the open fails at once and is reported; once a plain file is there it is written."""
    path = tmp_path / "audit.jsonl"
    os.mkfifo(path)
    said: list[str | None] = []
    audit = AuditFile(path, 1_000_000, on_problem=said.append)
    audit.start()
    try:
        audit.put(event(1))
        audit.flush(slow(5))
        assert len(said) == 1 and said[0] is not None and str(path) in said[0]
        assert audit.lines_lost == 1 and audit.lines_written == 0
        path.unlink()
        audit.put(event(2))
        audit.flush(slow(5))
        assert said[1:] == [None]
        assert [d["command"] for d in lines(path)] == ["P 2 0"]
    finally:
        audit.stop()


def test_stopping_with_the_writer_hung_on_its_disk_gives_up_after_its_timeout(
    tmp_path: Path,
) -> None:
    """Rule 4: ``stop`` writes what is queued, but a writer hung on its disk (an NFS mount
    gone) with the queue full must not hang the bridge's shutdown: it waits ``timeout_s``."""
    audit = AuditFile(tmp_path / "audit.jsonl", 1_000_000, queue_lines=2)
    disk, in_writer = threading.Event(), threading.Event()

    def stuck(batch: list[str]) -> tuple[int, OSError | None]:
        in_writer.set()
        disk.wait()  # the hang under test, ended by the test itself below
        return len(batch), None

    audit._append = stuck  # type: ignore[method-assign]
    audit.start()
    audit.put(event(0))
    assert in_writer.wait(slow(60))
    audit.put(event(1))
    audit.put(event(2))  # the queue is full now
    stopped = threading.Event()
    stopper = threading.Thread(target=lambda: (audit.stop(0.5), stopped.set()), daemon=True)
    stopper.start()
    try:
        assert stopped.wait(slow(60)), "stop waited for a disk that never answers"
    finally:
        disk.set()
        stopper.join()


FULL_DISK = r"""
import json, resource, signal, sys
from dataclasses import replace
from pathlib import Path
from bridge.runtime.audit import AuditFile
from bridge.core.model import AuditEvent, Origin, Source

path, limit = Path(sys.argv[1]), int(sys.argv[2])
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # past the limit: EFBIG, as ENOSPC on a full disk
soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
audit = AuditFile(path, 1_000_000)
audit.start()
resource.setrlimit(resource.RLIMIT_FSIZE, (limit, hard))  # the disk holds `limit` bytes
origin = Origin(Source.ROTCTLD, None, "192.168.1.20")
for n in range(8):
    audit.put(AuditEvent(1_790_000_000.0 + n, "rotor", origin, f"P {n} 0", "executed", 90.0))
    audit.flush()
resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))  # space again
audit.put(AuditEvent(1_790_000_100.0, "rotor", origin, "P 100 0", "executed", 90.0))
audit.flush()
audit.stop()
print(json.dumps([audit.lines_written, audit.lines_lost, audit.write_failures]))
"""


def test_a_full_disk_leaves_no_torn_line_and_the_lines_lost_are_counted(tmp_path: Path) -> None:
    """A real file system that runs out of room in the middle of a line (RLIMIT_FSIZE, in a
    process of its own: the write is short, then fails): the file is cut back to the last whole
    line, every line in it is JSON, and the first line written once there is room again says
    how many were lost."""
    path = tmp_path / "audit.jsonl"
    one = len(json.dumps(event(0).as_dict(), separators=(",", ":"))) + 1
    limit = 3 * one + one // 2  # three lines and half of the fourth
    done = subprocess.run(
        [sys.executable, "-c", FULL_DISK, str(path), str(limit)],
        capture_output=True,
        text=True,
        timeout=slow(60),
        check=True,
    )
    written, lost, failures = json.loads(done.stdout.splitlines()[-1])
    assert (written, lost, failures) == (4, 5, 5)
    text = path.read_text()
    assert text.endswith("\n")
    docs = lines(path)  # every line whole
    assert [d["command"] for d in docs] == ["P 0 0", "P 1 0", "P 2 0", "P 100 0"]
    assert docs[-1]["dropped"] == 5 and "dropped" not in docs[2]


def test_a_short_write_is_cut_back_and_counted(tmp_path: Path) -> None:
    """A disk that takes part of a line and then says nothing wrong (a short write, no error):
    the part is cut away and the line counted lost, said in the next line written."""
    path = tmp_path / "audit.jsonl"
    writes = 0

    def short_once(fd: int, data: bytes) -> int:
        nonlocal writes
        writes += 1
        return os.write(fd, data[:10] if writes == 2 else data)

    said: list[str | None] = []
    audit = AuditFile(path, 1_000_000, on_problem=said.append, os_write=short_once)
    audit.start()
    try:
        for n in range(3):
            audit.put(event(n))
            audit.flush()
    finally:
        audit.stop()
    assert [(d["command"], d.get("dropped")) for d in lines(path)] == [
        ("P 0 0", None),
        ("P 2 0", 1),
    ]
    assert (audit.lines_written, audit.lines_lost, audit.write_failures) == (2, 1, 1)
    assert said[0] is not None and "short write" in said[0] and said[1:] == [None]


def _said(origin: Origin, n: int, command: str, result: str, *, halt: bool = False) -> AuditEvent:
    return AuditEvent(1_790_000_000.0 + n, "rotor", origin, command, result, 90.0, halt)


def test_a_flood_of_stops_cannot_roll_the_line_of_who_turned_the_rotor_out_of_the_file(
    tmp_path: Path,
) -> None:
    """Rule 6 (an attack pass: console STOPs at 1,000 a second rolled all four files over in
    25 s, and the move of a minute before was gone): a flood from one sender is its first
    lines and one line with its count and time span; another sender's refusals are their own
    run; the move, the lease change and the lock change are each a line of their own, in the
    current file, however long the flood; R/audit gets what the file gets."""
    path = tmp_path / "audit.jsonl"
    one = len(audit_line(event(10).as_dict())) + 1
    clock = FakeClock()
    published: list[AuditEvent] = []
    trail = AuditTrail(path, 40 * one, lambda _r, e: published.append(e), [], clock=clock)
    holder = Origin(Source.MQTT, "DL1ABC")
    neighbour = Origin(Source.WEB, None, "192.168.1.66")
    other = Origin(Source.ROTCTLD, None, "192.168.1.20")
    audited = trail.of("rotor")
    trail.start()
    try:
        audited(_said(holder, 0, "claim", "executed"))
        audited(_said(holder, 1, "target az 200", "executed"))
        for n in range(2, 2002):  # the flood: a STOP and a refused move, over and over
            audited(_said(neighbour, n, "console: stop", "executed", halt=True))
            audited(_said(other, n, f"P {n % 360} 0", "refused: DL1ABC holds the rotator"))
            clock.t += 1 / 32  # 32 a second from each: a minute of it by n = 1922
            if n == 1500:
                audited(_said(holder, n, "lock ON", "executed"))  # amid the flood
        clock.t += QUIET_S  # quiet again: the runs end
        trail.tick()
        trail.flush()
    finally:
        trail.stop()
    got = [json.loads(line) for line in path.read_text().splitlines()]
    assert not path.with_name("audit.jsonl.1").exists()  # 4,003 events, not 40 lines
    assert [(d["command"], d["time"]) for d in got if d["operator"] == "DL1ABC"] == [
        ("claim", 1_790_000_000.0),
        ("target az 200", 1_790_000_001.0),
        ("lock ON", 1_790_001_500.0),
    ]
    stops = [d for d in got if d["operator"] == "web 192.168.1.66"]
    # the first five as they came, then what a minute of it was, then the rest of it
    assert [d.get("count") for d in stops] == [None] * FREE_LINES + [1915, 80]
    assert (stops[-2]["first"], stops[-2]["last"]) == (1_790_000_007.0, 1_790_001_921.0)
    assert (stops[-1]["first"], stops[-1]["last"]) == (1_790_001_922.0, 1_790_002_001.0)
    assert stops[-1]["command"] == "console: stop" and stops[-1]["result"] == "executed"
    refusals = [d for d in got if d["operator"] == "rotctld 192.168.1.20"]
    assert [d.get("count") for d in refusals] == [None] * FREE_LINES + [1915, 80]
    assert refusals[-1]["command"] == "P 201 0"  # the last of them (n = 2001), whole
    assert [e.as_dict() for e in published] == got


def test_senders_beyond_counting_fold_by_interface(tmp_path: Path) -> None:
    """Rule 6: an operator name per message makes no run of its own past MOST_RUNS (here 2):
    the rest fold by interface and kind, the line ``mixed``, named by the interface; and go on
    doing so while that crowd's run goes on, though the first names' runs ended (a name used
    once each, ten a second: a line each after their runs' QUIET_S, without that)."""
    clock = FakeClock()
    published: list[AuditEvent] = []
    trail = AuditTrail(
        None, 0, lambda _r, e: published.append(e), [], clock=clock, runs=Runs(free=1, most=2)
    )
    audited = trail.of("rotor")
    for n in range(100):
        audited(_said(Origin(Source.MQTT, f"X{n}"), n, "target az 1", "refused: locked"))
        clock.t += 0.125
    clock.t += QUIET_S
    trail.tick()
    assert [(e.origin.who, e.count, e.mixed) for e in published] == [
        ("X0", 1, False),
        ("X1", 1, False),
        ("X2", 1, False),  # the interface's run: its first line is written as it came
        ("mqtt", 97, True),
    ]
    assert published[-1].as_dict()["mixed"] is True


def test_open_runs_say_their_counts_when_the_bridge_stops(tmp_path: Path) -> None:
    path = tmp_path / "audit.jsonl"
    trail = AuditTrail(path, 1_000_000, lambda _r, _e: None, [], clock=FakeClock())
    trail.start()
    neighbour = Origin(Source.WEB, None, "192.168.1.66")
    for n in range(FREE_LINES + 3):
        trail.of("rotor")(_said(neighbour, n, "console: stop", "executed", halt=True))
    trail.stop()
    last = lines(path)[-1]
    assert (last["count"], last["first"], last["last"]) == (3, 1_790_000_005.0, 1_790_000_007.0)


def test_a_run_says_when_its_summary_is_due_and_no_run_nothing(tmp_path: Path) -> None:
    """Rule 7, in virtual time: what the ticker waits for. No run open (nothing yet, or only
    moves): nothing to wait for. A run: its QUIET_S after its latest event, or its SPAN_S
    after it began when it goes on that long; due at that very moment, not a tick later."""
    runs = Runs()
    neighbour = Origin(Source.WEB, None, "192.168.1.66")
    assert runs.left(100.0) is None
    runs.offer("rotor", _said(neighbour, 0, "target az 10", "executed"), 100.0)
    assert runs.left(100.0) is None  # a move opens no run
    runs.offer("rotor", _said(neighbour, 1, "stop", "executed", halt=True), 100.0)
    assert runs.left(100.0) == QUIET_S
    assert runs.left(103.0) == QUIET_S - 3
    for n in range(2, 60):  # a stop a second: the run goes on, its minute comes first
        runs.offer("rotor", _said(neighbour, n, "stop", "executed", halt=True), 100.0 + n)
    assert runs.left(159.0) == 1.0  # began at 100: SPAN_S
    assert runs.due(159.5) == []  # not before...
    assert runs.left(160.0) == 0.0
    (summary,) = runs.due(160.0)  # ...and then at once
    assert summary[1].count == 60 - FREE_LINES - 1
    assert runs.left(160.0) == QUIET_S - 1  # quiet since 159
    assert runs.left(164.0) == 0.0
    assert runs.due(164.0) == [] and runs.left(164.0) is None  # ended, nothing left counted


def test_an_idle_trail_never_wakes_its_ticker(tmp_path: Path) -> None:
    """Rule 7: with no run open the ticker sleeps without a deadline (it woke once a second
    for nothing); a move leaves it asleep; the first refusal wakes it, to sleep until that
    run's summary is due; the stop wakes it at once and still says the open run's count."""
    published: list[AuditEvent] = []
    trail = AuditTrail(
        tmp_path / "audit.jsonl",
        1_000_000,
        lambda _r, e: published.append(e),
        [],
        clock=FakeClock(),
        runs=Runs(free=1),
    )
    audited = trail.of("rotor")
    other = Origin(Source.ROTCTLD, None, "192.168.1.20")
    trail.start()
    try:
        wait_until(lambda: trail.ticker_asleep, what="the ticker asleep")
        assert (trail.ticker_timeout, trail.ticker_wakeups) == (None, 0)  # until woken
        audited(_said(other, 0, "P 10 0", "executed"))  # a move: no run, nothing to say
        audited(_said(other, 1, "P 20 0", "refused: locked"))
        wait_until(lambda: trail.ticker_wakeups == 1 and trail.ticker_asleep, what="woken once")
        assert trail.ticker_timeout == QUIET_S  # (virtual time stands still)
        audited(_said(other, 2, "P 30 0", "refused: locked"))  # folded
    finally:
        trail.stop()
    assert not trail._ticker.is_alive()  # the stop woke it: no deadline to wait out
    assert [(e.command, e.count) for e in published] == [
        ("P 10 0", 1),
        ("P 20 0", 1),
        ("P 30 0", 1),  # the count the stop said: one folded, its first and last times
    ]
    assert published[-1].first_unix == 1_790_000_002.0


def test_a_run_is_summed_up_by_the_ticker_once_it_is_quiet(tmp_path: Path) -> None:
    """Rule 7 on the real clock: the ticker, woken by the run's first event, says its summary
    by itself once it has been quiet for its QUIET_S, not before, and sleeps again."""
    published: list[tuple[float, AuditEvent]] = []
    trail = AuditTrail(
        None,
        0,
        lambda _r, e: published.append((time.monotonic(), e)),
        [],
        runs=Runs(free=1, quiet_s=0.2),
    )
    audited = trail.of("rotor")
    other = Origin(Source.ROTCTLD, None, "192.168.1.20")
    trail.start()
    try:
        for n in range(4):
            audited(_said(other, n, f"P {n} 0", "refused: locked"))
        last = time.monotonic()
        wait_until(lambda: len(published) == 2, what="the run's summary")
        wait_until(lambda: trail.ticker_asleep and trail.ticker_timeout is None, what="asleep")
    finally:
        trail.stop()
    said_at, summary = published[-1]
    assert (summary.command, summary.count) == ("P 3 0", 3)
    assert said_at - last >= 0.2


def test_a_crowd_line_says_how_many_senders_and_names_the_first(tmp_path: Path) -> None:
    """Rule 8: a crowd's line (``mixed``) says how many different senders its count stands for
    and names the first of them as they came, an operator and an address both where a sender
    gave both; counted up to a bound, beyond which it says there were more; and each minute's
    line counts its own minute's senders (it said the interface alone: after an attack, the
    operator could not learn who)."""
    clock = FakeClock()
    published: list[AuditEvent] = []
    runs = Runs(free=1, most=1, counted=6, named=3)
    trail = AuditTrail(None, 0, lambda _r, e: published.append(e), [], clock=clock, runs=runs)
    audited = trail.of("rotor")
    web = [Origin(Source.WEB, None, f"192.168.1.{n}") for n in range(10)]
    audited(_said(web[9], 0, "console: stop", "executed", halt=True))  # the one run there is
    senders = [web[1], web[2], Origin(Source.WEB, "DL1ABC", "10.0.0.7"), web[2], web[3]]
    for n, origin in enumerate(senders + senders + web[4:8], 1):  # 2 + 4 distinct more: 8
        audited(_said(origin, n, "console: stop", "executed", halt=True))
        clock.t += 0.5
    clock.t += QUIET_S
    trail.tick()
    crowd = [e.as_dict() for e in published if e.mixed]
    assert len(crowd) == 1
    line = crowd[0]
    assert (line["operator"], line["count"]) == ("web", 13)  # 14 in the crowd, the first written
    assert line["senders"] == 6 and line["more_senders"] is True  # web 6 and 7: beyond
    assert line["names"] == ["web 192.168.1.2", "DL1ABC (10.0.0.7)", "web 192.168.1.3"]
    assert published[1].origin.who == "web 192.168.1.1"  # the crowd's first, written whole
    published.clear()
    for n in range(2 * int(SPAN_S)):  # a crowd that goes on, one sender in its second minute
        audited(_said(web[9], n, "console: stop", "executed", halt=True))  # the run, again
        origin = web[1 + n % 3] if n < SPAN_S else web[5]
        audited(_said(origin, n, "console: stop", "executed", halt=True))
        clock.t += 1.0
        trail.tick()
    clock.t += QUIET_S
    trail.tick()
    minutes = [e.as_dict() for e in published if e.mixed]
    assert [(d["count"], d["senders"], d["names"]) for d in minutes] == [
        (59, 3, ["web 192.168.1.2", "web 192.168.1.3", "web 192.168.1.1"]),
        (60, 1, ["web 192.168.1.5"]),
    ]
    assert not any("more_senders" in d for d in minutes)


def test_the_ticker_sleeps_a_tick_at_least_while_runs_are_open(tmp_path: Path) -> None:
    """Rule 7: a summary due sooner than TICK_S does not wake the ticker sooner (a crowd's
    runs, due one after the other, would wake it for each): it is up to TICK_S late."""
    clock = FakeClock()
    trail = AuditTrail(None, 0, lambda _r, _e: None, [], clock=clock)
    other = Origin(Source.ROTCTLD, None, "192.168.1.20")
    trail.of("rotor")(_said(other, 0, "P 20 0", "refused: locked"))  # before the ticker runs
    clock.t += QUIET_S - TICK_S / 2  # its summary due in half a tick
    trail.start()
    try:
        wait_until(lambda: trail.ticker_asleep, what="the ticker asleep")
        assert trail.ticker_timeout == TICK_S
    finally:
        trail.stop()


def _target(origin: Origin, n: float, command: str) -> AuditEvent:
    return replace(
        _said(origin, 0, command, "executed"), time_unix=1_790_000_000.0 + n, same_again=True
    )


def test_the_same_target_sent_over_and_over_cannot_roll_the_trail_over(tmp_path: Path) -> None:
    """Rule 9 (measured: a loop republishing a target 50 times a second wrote 50 lines a
    second, 8 KB, and the four files of the default size rolled over in 8 minutes): the same
    target from the same sender, nothing else carried out in between, is its first lines and a
    count; the target sent again after another's target or a stop is written (it turns the
    rotor back), a refusal between two changes nothing; different targets are each a line."""
    path = tmp_path / "audit.jsonl"
    one = len(audit_line(event(10).as_dict())) + 1
    clock = FakeClock()
    trail = AuditTrail(path, 60 * one, lambda _r, _e: None, [], clock=clock)
    loop = Origin(Source.MQTT, "node-red")
    holder = Origin(Source.MQTT, "DL1ABC")
    other = Origin(Source.ROTCTLD, None, "192.168.1.20")
    audited = trail.of("rotor")
    trail.start()
    try:
        for n in range(3000):  # a minute at 50 a second, the same target...
            audited(_target(loop, n / 50, "target '200'"))
            if n == 1000:  # ...a refusal amid it changes nothing...
                audited(_said(other, 20, "P 10 0", "refused: DL1ABC holds the rotator"))
            if n == 2000:  # ...another's target does: the next one turns the rotor back
                audited(_target(holder, 40, "target '100'"))
            clock.t += 1 / 50
        audited(_said(holder, 60, "stop", "executed", halt=True))
        audited(_target(loop, 61, "target '200'"))  # after a stop: turns it again
        for n in range(3):  # a sweep: every target a line
            audited(_target(loop, 62 + n, f"target '{210 + n}'"))
        clock.t += QUIET_S
        trail.tick()
        trail.flush()
    finally:
        trail.stop()
    assert not path.with_name("audit.jsonl.1").exists()  # 3,006 events, not 60 lines
    written = lines(path)
    loop = ("node-red", "target '200'", None)
    assert [(d["operator"], d["command"], d.get("count")) for d in written] == [
        *[loop] * (1 + FREE_LINES),  # the first, then the first of its repeats
        ("rotctld 192.168.1.20", "P 10 0", None),
        ("DL1ABC", "target '100'", None),
        loop,  # it turned the rotor back
        ("DL1ABC", "stop", None),
        loop,  # it turned the rotor again
        ("node-red", "target '210'", None),
        ("node-red", "target '211'", None),
        ("node-red", "target '212'", None),
        ("node-red", "target '200'", 3000 - FREE_LINES - 2),  # the rest, counted
    ]
    assert (written[-1]["first"], written[-1]["last"]) == (1_790_000_000.12, 1_790_000_059.98)


def test_halts_that_changed_nothing_fold_each_by_its_command_and_a_lock_that_locked_is_a_line(
    tmp_path: Path,
) -> None:
    """Rule 10 (attack 15: 400 lock ONs while locked were 400 lines, so were track and follow
    OFFs with nothing to end): a loop sending a lock ON while locked and a tracking OFF with
    nothing tracked, between its stops, is the first lines of each command and a count of each
    (its stops apart, as rule 6 has them); another sender's lock ON that locked, amid it, is a
    line of its own; R/audit gets the same lines, the counts among the routine ones (service.py
    rule 8's budget for refusals and stops)."""
    path = tmp_path / "audit.jsonl"
    clock = FakeClock()
    published: list[AuditEvent] = []
    trail = AuditTrail(path, 1_000_000, lambda _r, e: published.append(e), [], clock=clock)
    loop = Origin(Source.MQTT, "node-red")
    holder = Origin(Source.MQTT, "DL1ABC")
    audited = trail.of("rotor")
    trail.start()
    try:
        for n in range(300):
            audited(replace(_said(loop, n, "lock ON", "executed"), unchanged=True))
            audited(replace(_said(loop, n, "track off", "executed"), unchanged=True))
            audited(_said(loop, n, "stop", "executed", halt=True))
            if n == 150:
                audited(_said(holder, n, "lock ON", "executed"))  # it locked: a line
            clock.t += 0.01
        clock.t += QUIET_S
        trail.tick()
        trail.flush()
    finally:
        trail.stop()
    written = lines(path)
    assert [(d["operator"], d["command"], d.get("count")) for d in written] == [
        *[
            ("node-red", c, None)
            for _ in range(FREE_LINES)
            for c in ("lock ON", "track off", "stop")
        ],
        ("DL1ABC", "lock ON", None),
        ("node-red", "lock ON", 300 - FREE_LINES),
        ("node-red", "track off", 300 - FREE_LINES),
        ("node-red", "stop", 300 - FREE_LINES),
    ]
    assert [e.as_dict() for e in published] == written
    assert [e.routine for e in published if e.count > 1] == [True] * 3
    assert not next(e for e in published if e.origin == holder).routine
