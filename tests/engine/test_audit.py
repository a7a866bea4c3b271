"""The audit file on a real file system: lines, rotation by size, a full disk (/dev/full gives
ENOSPC on every write), and coming back when the path is writable again."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from pathlib import Path

from bridge.core.model import AuditEvent, Origin, Source
from bridge.runtime.audit import QUEUE_LINES, AuditFile, AuditTrail
from tests.support.waiting import slow


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
