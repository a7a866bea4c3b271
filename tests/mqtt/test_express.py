"""The stop express (interfaces/mqtt/express.py): what it writes and when (rule 3), the ports it
holds and gives back (rule 5), and that its failures are said (rule 6). The child's decisions are
run here on a socket pair and a pipe standing in for the port; the parent's on child processes that
misbehave. The real path (broker, express, pty, a held bridge) is
tests/integration/test_stop_express.py."""

from __future__ import annotations

import contextlib
import json
import logging
import os
import signal
import socket
import sys
import threading
from collections.abc import Iterator
from typing import Any

import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

import bridge.interfaces.mqtt.express as express_module
from bridge.interfaces.mqtt.express import (
    DROP_WAIT_S,
    FINISH_WAIT_S,
    GAP_S,
    READ_WAIT_S,
    Express,
    Sync,
    _Child,
    _Outbox,
    express_client_id,
)
from bridge.protocols import REGISTRY
from bridge.settings.mqtt import MqttSettings
from tests.support.rig import EASYCOMM_MODELS, GS232_MODELS
from tests.support.waiting import slow, wait_until

SETTINGS = MqttSettings(host="127.0.0.1", port=1, client_id="rotor-shack")
TOPICS = {
    "rotor/a/stop": ("a", "stop"),
    "rotor/a/lock": ("a", "lock"),
    "rotor/b/stop": ("b", "stop"),
    "rotor/c/stop": ("c", "stop"),  # (a SPID, say: no frame the express may write)
}
GROUPS = {"rotor/stack/stop": ["a", "b"], "rotor/all/stop": ["a", "c"]}
SYNC = "rotor/bridge/fence/express"


class Port:
    """A pipe standing in for a controller's port: what the express wrote to it."""

    def __init__(self) -> None:
        self.r, self.w = os.pipe()
        os.set_blocking(self.r, False)

    def written(self) -> bytes:
        try:
            return os.read(self.r, 4096)
        except BlockingIOError:
            return b""


class ChildRig:
    def __init__(self, mqtt311: bool) -> None:
        self.mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        config = {
            "topics": TOPICS,
            "frames": {"a": b";".hex(), "b": b"S\r".hex()},
            "mqtt311": mqtt311,
            "mqtt": SETTINGS.model_dump(mode="json"),
            "client_id": "rfast-shack",
            "groups": GROUPS,
            "sync_topic": SYNC,
        }
        self.child = _Child(theirs, config)
        self.published: list[str] = []  # its sync words, as published (rule 8)
        self.child.link.publish = lambda topic, payload: self.published.append(payload)
        self.thread = threading.Thread(target=self.child.serve, daemon=True)
        self.thread.start()
        self.connect()

    def connect(self) -> None:
        """Its connection accepted and subscribed, its first word back: it writes (rule 8)."""
        self.child._linked(True)
        self.child._subscribed()
        self.back()
        assert self.word() == {"op": "up"}

    def back(self) -> None:
        """Every word it published comes back, in order (the broker's copy)."""
        words, self.published[:] = list(self.published), []
        for payload in words:
            self.child.on_message(SYNC, payload.encode(), False, None, None)

    def ask(self, n: int, again: bool = False) -> None:
        self.mine.send(json.dumps({"op": "sync", "n": n, "again": again}).encode())

    def word(self) -> dict[str, object]:
        self.mine.settimeout(slow(5))
        word: dict[str, object] = json.loads(self.mine.recv(65536))
        return word

    def hand(self, rid: str, n: int, port: Port) -> None:
        socket.send_fds(
            self.mine, [json.dumps({"op": "port", "rotator": rid, "n": n}).encode()], [port.w]
        )
        assert self.word() == {"op": "held", "rotator": rid, "n": n}

    def stop(self, topic: str, payload: bytes = b"STOP", retain: bool = False) -> None:
        self.child.on_message(topic, payload, retain, None, None)


@pytest.fixture
def rig() -> Iterator[ChildRig]:
    r = ChildRig(mqtt311=False)
    yield r
    r.mine.close()
    r.thread.join(slow(5))


def test_a_stop_is_the_rotators_stop_frame_written_at_once_whatever_its_payload(
    rig: ChildRig,
) -> None:
    port = Port()
    rig.hand("a", 1, port)
    now = [100.0]
    rig.child.clock = lambda: now[0]
    for payload in (b"", b"STOP", b"anything at all"):
        rig.stop("rotor/a/stop", payload)
        now[0] += GAP_S
    assert port.written() == b";;;"
    assert rig.word() == {"op": "wrote", "rotator": "a", "t": 100.0}


def test_a_flood_of_stops_is_one_frame_a_rotator_in_a_gap(rig: ChildRig) -> None:
    port, now = Port(), [100.0]
    rig.child.clock = lambda: now[0]
    rig.hand("a", 1, port)
    for _ in range(1000):
        rig.stop("rotor/a/stop")
        rig.stop("rotor/a/lock", b"ON")
    assert port.written() == b";"
    now[0] += GAP_S
    rig.stop("rotor/a/stop")
    assert port.written() == b";"
    # and said to the bridge once a gap each: a frame, a lock ON (rule 11; a word for each of
    # a flood filled the socket, and the express's next send waited for room)
    words = [rig.word() for _ in range(3)]
    assert words == [
        {"op": "wrote", "rotator": "a", "t": 100.0},
        {"op": "locked", "rotator": "a", "t": 100.0, "operator": None},
        {"op": "wrote", "rotator": "a", "t": 100.0 + GAP_S},
    ]
    rig.mine.setblocking(False)
    with pytest.raises(BlockingIOError):
        rig.mine.recv(65536)


def test_a_stop_it_writes_no_frame_for_is_said_once_a_gap(rig: ChildRig) -> None:
    """Rule 11, an attack pass: a group's stop heard by the express alone (the bridge's
    connections not back after a broker restart) stopped the member it writes for, and its
    SPID turned on. A stop it writes no frame for, a member's or a rotator's own, is said (the
    bridge carries it out if it never had it), once a gap in a flood."""
    now = [100.0]
    rig.child.clock = lambda: now[0]
    port = Port()
    rig.hand("a", 1, port)
    rig.stop("rotor/all/stop")
    assert port.written() == b";"
    assert rig.word() == {"op": "wrote", "rotator": "a", "t": 100.0}
    assert rig.word() == {"op": "heard", "rotator": "c", "t": 100.0}
    for _ in range(100):
        rig.stop("rotor/c/stop")
    now[0] += GAP_S
    rig.stop("rotor/c/stop")
    assert rig.word() == {"op": "heard", "rotator": "c", "t": 100.0 + GAP_S}
    rig.stop("rotor/b/stop")  # b's port not handed over (unplugged, say): said, not written
    assert rig.word() == {"op": "heard", "rotator": "b", "t": 100.0 + GAP_S}
    rig.mine.setblocking(False)
    with pytest.raises(BlockingIOError):
        rig.mine.recv(65536)


def test_a_lock_on_stops_a_lock_off_or_junk_does_not(rig: ChildRig) -> None:
    port = Port()
    rig.child.clock = lambda: 100.0
    rig.hand("a", 1, port)
    for payload in (b"OFF", b"maybe", b"0"):
        rig.stop("rotor/a/lock", payload)
    assert port.written() == b""
    rig.stop("rotor/a/lock", b"ON")
    assert port.written() == b";"
    # rule 11: the frame said, and the lock ON itself, with who sent it (the bridge sets it if
    # it never had it: its audit trail names them)
    assert rig.word()["op"] == "wrote"
    assert rig.word() == {"op": "locked", "rotator": "a", "t": 100.0, "operator": None}
    rig.child.clock = lambda: 101.0
    rig.child.on_message("rotor/a/lock", b"ON", False, "alice", None)
    assert rig.word() == {"op": "wrote", "rotator": "a", "t": 101.0, "operator": "alice"}
    assert rig.word() == {"op": "locked", "rotator": "a", "t": 101.0, "operator": "alice"}


def test_a_stop_written_or_heard_names_who_sent_it(rig: ChildRig) -> None:
    """Rule 11, an attack pass: the bridge carries out a stop the express alone had, and its
    audit trail named ``mqtt``, not the remote operator who sent it."""
    port = Port()
    rig.child.clock = lambda: 100.0
    rig.hand("a", 1, port)
    rig.child.on_message("rotor/a/stop", b"STOP", False, "DL1ABC", None)
    assert port.written() == b";"
    assert rig.word() == {"op": "wrote", "rotator": "a", "t": 100.0, "operator": "DL1ABC"}
    rig.child.on_message("rotor/c/stop", b"STOP", False, "DL1ABC", None)  # no port of its own
    assert rig.word() == {"op": "heard", "rotator": "c", "t": 100.0, "operator": "DL1ABC"}


def test_a_lock_on_replayed_under_311_is_not_said_to_the_bridge() -> None:
    """Rule 11 with rule 3's replay: a 3.1.1 broker's replay of a retained lock ON is no lock
    ON heard now (the bridge's connections get the same replay and set it themselves)."""
    old = ChildRig(mqtt311=True)
    port = Port()
    old.hand("a", 1, port)
    old.stop("rotor/a/lock", b"ON", retain=True)
    assert port.written() == b""
    old.mine.setblocking(False)
    with pytest.raises(BlockingIOError):
        old.mine.recv(65536)
    old.mine.close()


def test_a_rotator_whose_port_it_does_not_hold_gets_nothing(rig: ChildRig) -> None:
    port = Port()
    rig.hand("a", 1, port)
    rig.stop("rotor/b/stop")  # b's port was never handed over (closed, or not open yet)
    rig.stop("rotor/c/stop")  # not a rotator of the express (rule 4)
    assert port.written() == b""


def test_a_retained_stop_is_written_under_mqtt5_not_a_replay_under_311(rig: ChildRig) -> None:
    port = Port()
    rig.hand("a", 1, port)
    rig.stop("rotor/a/stop", b"", retain=True)  # a retained stop being deleted: no command
    assert port.written() == b""
    rig.stop("rotor/a/stop", retain=True)  # MQTT 5: published retained, live (never replayed)
    assert port.written() == b";"
    old = ChildRig(mqtt311=True)
    port311 = Port()
    old.hand("a", 1, port311)
    old.stop("rotor/a/stop", retain=True)  # 3.1.1: the broker's replay (the session's, once)
    old.stop("rotor/a/stop")
    assert port311.written() == b";"
    old.mine.close()


def test_a_port_given_back_is_closed_and_written_to_no_more(rig: ChildRig) -> None:
    port = Port()
    rig.hand("a", 1, port)
    rig.mine.send(json.dumps({"op": "drop", "rotator": "a", "n": 1}).encode())
    assert rig.word() == {"op": "dropped", "rotator": "a", "n": 1}
    rig.stop("rotor/a/stop")
    os.close(port.w)  # the express's copy is closed: the pipe has no writer left
    assert os.read(port.r, 10) == b""


def test_a_late_word_about_an_older_port_leaves_the_newer_one(rig: ChildRig) -> None:
    old, new = Port(), Port()
    rig.hand("a", 1, old)
    rig.hand("a", 2, new)  # reopened (unplug, replug) before the old one's drop came
    rig.mine.send(json.dumps({"op": "drop", "rotator": "a", "n": 1}).encode())
    assert rig.word()["op"] == "dropped"
    rig.stop("rotor/a/stop")
    assert (old.written(), new.written()) == (b"", b";")


# -- rule 8: a late frame never stops a newer move -------------------------------------------
def linked() -> Sync:
    sync = Sync()
    sync.accepted()
    word = sync.subscribed()
    assert sync.read_back(word) == (None, None) and sync.writing
    return sync


def test_a_request_is_answered_by_a_word_published_after_it_not_by_one_out_before() -> None:
    sync = linked()
    assert sync.asked(1) == (None, 2)  # word 2 published after request 1 came
    assert sync.asked(2) == (None, None)  # word 2 is out: it was published before request 2
    assert sync.read_back(2) == (1, 3)  # answers 1; request 2 needs a word after it: 3
    assert sync.read_back(3) == (2, None)
    assert sync.read_back(3) == (None, None)  # (a duplicate, an earlier connection's word)


def test_a_word_the_broker_dropped_is_published_again_when_asked_again() -> None:
    sync = linked()
    assert sync.asked(1) == (None, 2)  # word 2 never comes back
    assert sync.asked(1, again=True) == (None, 3)
    assert sync.read_back(3) == (1, None)


def test_while_its_connection_is_down_a_request_is_answered_at_once() -> None:
    sync = Sync()
    assert sync.asked(1) == (1, None)  # nothing it reads later can be that old
    sync = linked()
    assert sync.asked(1) == (None, 2)
    assert sync.ended() == 1  # a connection that ends answers every request
    assert not sync.writing and sync.asked(2) == (2, None)


def test_an_answer_given_at_once_keeps_it_from_writing_until_a_newer_word_came_back() -> None:
    """Connected, its first word not back yet: a request is answered at once (it writes
    nothing now). A word published before that answer may come back before a stop the bridge
    read before asking: only a word published after the answer lets it write."""
    sync = Sync()
    sync.accepted()
    first = sync.subscribed()
    assert sync.asked(1) == (1, first + 1)
    assert sync.read_back(first) == (None, None) and not sync.writing
    assert sync.read_back(first + 1) == (None, None) and sync.writing


def test_words_a_broker_drops_are_not_kept_for_ever() -> None:
    """A broker that drops its words (an ACL): each stop's request is answered at once and a
    word published; a flood of stops must not leave a word kept for each (nor its mark)."""
    sync = Sync()
    sync.accepted()
    sync.subscribed()
    for n in range(1, 10_001):
        answer, word = sync.asked(n)
        assert answer == n and word is not None
    assert len(sync._out) <= 1
    assert sync.read_back(word) == (None, None) and sync.writing  # the newest still counts


def test_marks_of_words_a_broker_drops_are_not_kept_for_ever(rig: ChildRig) -> None:
    rig.child._linked(False)
    assert rig.word() == {"op": "down"}
    rig.child._linked(True)
    rig.child._subscribed()
    for n in range(1, 501):
        rig.ask(n)
        assert rig.word() == {"op": "synced", "n": n}
    assert len(rig.child._marks) <= 2


def test_a_stop_read_before_its_words_came_back_is_not_written_but_said_early(
    rig: ChildRig,
) -> None:
    """Rule 8: no frame before its word is back; rule 11: the stop said all the same, early (a
    CI run: the express back first after a broker restart dropped a STOP read in that round
    trip unsaid, the bridge's connections subscribed just after it, and the rotor turned on)."""
    port = Port()
    rig.child.clock = lambda: 100.0
    rig.hand("a", 1, port)
    rig.child._linked(False)  # the broker went away: every request answered from now on
    assert rig.word() == {"op": "down"}
    rig.child._linked(True)
    rig.child._subscribed()
    rig.child.on_message("rotor/a/stop", b"STOP", False, "DL1ABC", None)  # its word not back
    assert port.written() == b""  # it may not write
    said = {"op": "heard", "rotator": "a", "t": 100.0, "early": True, "operator": "DL1ABC"}
    assert rig.word() == said
    rig.stop("rotor/stack/stop")  # a group's: each member (a within its gap: said once)
    assert rig.word() == {"op": "heard", "rotator": "b", "t": 100.0, "early": True}
    rig.stop("rotor/a/lock", b"ON")
    assert rig.word() == {
        "op": "locked",
        "rotator": "a",
        "t": 100.0,
        "operator": None,
        "early": True,
    }
    rig.stop("rotor/a/lock", b"OFF")  # (no lock ON: nothing said)
    rig.back()
    assert rig.word() == {"op": "up"}
    rig.stop("rotor/a/stop")
    assert port.written() == b";"


def test_the_bridge_is_answered_after_the_stops_read_before_its_word(rig: ChildRig) -> None:
    """The order on its socket: the frame of a stop the broker had before the word, then the
    answer (the bridge's hold ends with it)."""
    port = Port()
    rig.hand("a", 1, port)
    rig.ask(7)
    wait_until(lambda: rig.published, 5, "its word published")
    rig.stop("rotor/a/stop")  # the stop the bridge read before asking
    rig.back()
    assert rig.word()["op"] == "wrote"
    assert rig.word() == {"op": "synced", "n": 7}
    assert port.written() == b";"


def test_a_word_forged_by_another_client_ends_no_hold(rig: ChildRig) -> None:
    """Anyone who may read its sync topic sees its words. A word forged from them (the next
    number), published before the bridge's STOP and so read before it, must not answer a
    request: the hold would end before the express read the STOP, and its late frame would
    stop a move published after it. Nor may a word another client left retained there."""
    port = Port()
    rig.hand("a", 1, port)
    rig.ask(1)
    seen = wait_until(lambda: rig.published, 5, "its word published")[0]
    token, _, number = seen.partition(" ")
    rig.back()
    assert rig.word() == {"op": "synced", "n": 1}
    rig.ask(2)
    wait_until(lambda: rig.published, 5, "its next word published")
    forged = f"{token} {int(number) + 1}".encode()
    rig.child.on_message(SYNC, forged, False, None, None)  # read before the STOP
    rig.child.on_message(SYNC, forged, True, None, None)  # (or replayed, retained)
    rig.stop("rotor/a/stop")  # the STOP, read late
    rig.back()  # then its own word
    assert rig.word()["op"] == "wrote"
    assert rig.word() == {"op": "synced", "n": 2}  # after the frame, not before it


def test_a_sync_word_whose_number_is_too_long_or_not_ascii_is_ignored(rig: ChildRig) -> None:
    """An attack pass: a word on its sync topic whose number has more digits than ``int`` reads
    (5000) raised ValueError on paho's thread: a traceback in the log for each one anyone
    allowed there published. Such a word is another's, as a forged one is (and so is one whose
    digits are not ASCII)."""
    port = Port()
    rig.hand("a", 1, port)
    rig.ask(1)
    seen = wait_until(lambda: rig.published, 5, "its word published")[0]
    token = seen.partition(" ")[0]
    for number in ("\u00b2", "9" * 5000, "\u0661"):
        rig.child.on_message(SYNC, f"{token} {number}".encode(), False, None, None)
    rig.back()
    assert rig.word() == {"op": "synced", "n": 1}


def test_a_group_stop_is_each_members_frame(rig: ChildRig) -> None:
    a, b = Port(), Port()
    rig.hand("a", 1, a)
    rig.hand("b", 2, b)
    rig.stop("rotor/stack/stop")
    assert (a.written(), b.written()) == (b";", b"S\r")
    assert {rig.word()["rotator"], rig.word()["rotator"]} == {"a", "b"}


def test_a_group_stop_from_a_long_operator_costs_no_member_its_frames_wait(
    rig: ChildRig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Rule 11: who sent a stop is named as an operator's name, and a user property that can be
    none is dropped before it costs the stop's thread anything. A STOP to a group whose
    ``operator`` held 21,845 U+FDFA (64 KiB, one ligature NFKC makes 18 characters) had all of
    it normalized, 393,210 characters, some 24 ms between one member's frame and the next's (a
    cold review: five members, the last one's stop ~0.1 s late, from anyone who may stop)."""
    import bridge.core.model as model

    worked: list[int] = []  # the length of each text normalized on the stop's path
    real = model.unicodedata

    class Counting:
        def __getattr__(self, name: str) -> Any:
            return getattr(real, name)

        @staticmethod
        def normalize(form: str, text: str) -> str:
            worked.append(len(text))
            return real.normalize(form, text)

    monkeypatch.setattr(model, "unicodedata", Counting())
    a, b = Port(), Port()
    rig.hand("a", 1, a)
    rig.hand("b", 2, b)
    rig.child.on_message("rotor/stack/stop", b"STOP", False, "\ufdfa" * 21845, None)
    assert (a.written(), b.written()) == (b";", b"S\r")
    words = [rig.word(), rig.word()]
    assert {w["rotator"] for w in words} == {"a", "b"}
    assert all("operator" not in w for w in words)  # no name of an operator
    assert max(worked, default=0) <= 4 * model.OPERATOR_CHARS


# -- rule 9: a frame is never left half-written ------------------------------------------------
def test_a_write_cut_short_by_a_full_buffer_is_finished(monkeypatch: pytest.MonkeyPatch) -> None:
    port, calls, write = Port(), [], os.write

    def short_first(fd: int, data: bytes) -> int:  # a tty whose output buffer had 1 byte left
        calls.append(data)
        return write(fd, data[:1] if len(calls) == 1 else data)

    monkeypatch.setattr(express_module.os, "write", short_first)
    rig = ChildRig(mqtt311=False)
    try:
        rig.hand("b", 1, port)
        rig.stop("rotor/b/stop")
        assert port.written() == b"S\r"  # whole: no frame of the session's lands inside it
        assert rig.word()["op"] == "wrote"
    finally:
        rig.mine.close()


def test_a_write_the_tty_refuses_whole_is_made_when_it_takes_bytes_again(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A tty refuses a non-blocking write outright while another writer of it is inside its own
    (the serial-lines thread writing the session's stop that instant): the express let its
    frame go and said nothing (a stop express test waited for it in vain under load)."""
    port, calls, write = Port(), [], os.write

    def refused_first(fd: int, data: bytes) -> int:
        calls.append(data)
        if len(calls) == 1:
            raise BlockingIOError
        return write(fd, data)

    monkeypatch.setattr(express_module.os, "write", refused_first)
    b_stopped_whole(port)


def b_stopped_whole(port: Port) -> None:
    """A stop of rotator b through an express that holds ``port``: its whole frame written on
    the port, and said."""
    rig = ChildRig(mqtt311=False)
    try:
        rig.hand("b", 1, port)
        rig.stop("rotor/b/stop")
        assert port.written() == b"S\r"
        assert rig.word()["op"] == "wrote"
    finally:
        rig.mine.close()


def test_a_write_the_tty_refuses_whole_is_tried_again_after_a_pause_not_in_a_spin(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The express runs ahead of the bridge's threads (rule 10): the writer inside its own write
    of the tty may be one of them, and a retry without a pause could keep it off the only core
    it has, so the express lets go of the core before each try again."""
    port, events, write = Port(), [], os.write

    def refused_thrice(fd: int, data: bytes) -> int:
        events.append("write")
        if events.count("write") <= 3:
            raise BlockingIOError
        return write(fd, data)

    def pause(seconds: float) -> None:
        events.append("pause")
        assert 0 < seconds <= 0.001

    monkeypatch.setattr(express_module.os, "write", refused_thrice)
    monkeypatch.setattr(express_module.time, "sleep", pause)
    b_stopped_whole(port)
    # the first refusal hands the frame to the wait for the tty (rule 9), each later one pauses
    # before the next try
    assert events == ["write", "write", "pause", "write", "pause", "write"]


def _stuck_a(
    monkeypatch: pytest.MonkeyPatch, rig: ChildRig, a: Port
) -> tuple[list[float], list[bool]]:
    """``a``'s tty takes nothing while ``full[0]`` (a stuck adapter, its buffer full) and
    nothing drains it: the express's waits pass in virtual time (``now[0]``)."""
    now, full = [100.0], [True]

    def waited(fd: int, timeout_s: float | None) -> bool:  # nothing drains a's tty
        now[0] += timeout_s or 0.0
        return False

    monkeypatch.setattr(express_module, "writable", waited)
    rig.child.clock = lambda: now[0]
    stuck, write = os.fstat(a.w).st_ino, rig.child.write  # (the express holds a copy)

    def full_for_a(fd: int, data: bytes) -> int:
        if full[0] and os.fstat(fd).st_ino == stuck:
            raise BlockingIOError
        return write(fd, data)

    rig.child.write = full_for_a
    return now, full


def test_a_members_stuck_tty_holds_up_no_other_members_frame_of_a_group_stop(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """One thread writes every rotator's frame: a group stop whose first member's tty takes
    nothing (a stuck adapter: its buffer full) waited out that member's whole wait, in virtual
    time here, before it wrote the second member's stop, which the express is for."""
    a, b = Port(), Port()
    rig = ChildRig(mqtt311=False)
    try:
        _stuck_a(monkeypatch, rig, a)
        rig.hand("a", 1, a)
        rig.hand("b", 2, b)
        rig.stop("rotor/stack/stop")
        assert b.written() == b"S\r"
        assert rig.word() == {"op": "wrote", "rotator": "b", "t": 100.0}  # at once, not after a's
    finally:
        rig.mine.close()


def test_a_tty_found_stuck_is_waited_for_no_more_until_it_takes_a_frame(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A rotator whose tty took nothing for the whole wait (a dead adapter, its buffer full)
    cost the express's one thread that wait again at each of its later stops, so another
    rotator's stop that came behind one waited too (in virtual time here). Once found stuck,
    a frame it refuses whole is let go at once, until it takes bytes again (or a new port)."""
    a, b = Port(), Port()
    rig = ChildRig(mqtt311=False)
    try:
        now, full = _stuck_a(monkeypatch, rig, a)
        rig.hand("a", 1, a)
        rig.hand("b", 2, b)
        rig.stop("rotor/a/stop")  # found stuck: waited for once
        first = 100.0
        now[0] += GAP_S
        came = now[0]
        rig.stop("rotor/a/stop")
        rig.stop("rotor/b/stop")
        assert b.written() == b"S\r"
        # (a's stops, no frame of them taken, are said: rule 11, the bridge's own if only
        # the express heard them)
        assert rig.word() == {"op": "heard", "rotator": "a", "t": first}
        assert rig.word() == {"op": "heard", "rotator": "a", "t": came}
        assert rig.word() == {"op": "wrote", "rotator": "b", "t": came}  # not after a's wait
        full[0] = False  # a's line moves again: its frame goes, and it is waited for again
        now[0] += GAP_S
        rig.stop("rotor/a/stop")
        assert a.written() == b";"
        assert rig.word() == {"op": "wrote", "rotator": "a", "t": now[0]}
    finally:
        rig.mine.close()


def test_a_frame_the_port_never_finishes_taking_is_said(rig: ChildRig) -> None:
    port, now = Port(), [100.0]
    rig.child.clock = lambda: now[0]

    def stuck(fd: int, data: bytes) -> int:
        if data == b"S\r":
            return os.write(fd, b"S")
        now[0] += FINISH_WAIT_S  # the line takes nothing more
        raise BlockingIOError

    rig.child.write = stuck
    rig.hand("b", 1, port)
    rig.stop("rotor/b/stop")
    assert rig.word() == {"op": "half", "rotator": "b"}
    # rule 11, a review: a half frame is no stop (a GS-232's S then M180 is SM180): said as
    # heard, so the bridge carries the stop out if only the express had it
    assert rig.word() == {"op": "heard", "rotator": "b", "t": 100.0}


def test_client_id_is_the_lanes_rule_with_its_own_mark() -> None:
    assert express_client_id(SETTINGS) == "rotor-shack-fast"
    long = MqttSettings(client_id="a-very-long-client-id-x")
    assert len(express_client_id(long)) <= 23 and express_client_id(long).endswith("-fast")


# -- the parent's side: failures are said (rule 6) ----------------------------------------------
class Problems:
    """What the express says of its problems, from its threads; read from the test's (a lock:
    a CI run read the dictionary while the watchdog's thread added to it)."""

    def __init__(self) -> None:
        self.said: dict[str, bool] = {}
        self.changed = threading.Event()
        self._lock = threading.Lock()

    def __call__(self, text: str, on: bool) -> None:
        with self._lock:
            self.said[text] = on
        self.changed.set()

    def on(self) -> list[str]:
        with self._lock:
            return [t for t, on in self.said.items() if on]

    def texts(self) -> list[str]:
        with self._lock:
            return list(self.said)


def express(
    command: list[str],
    problems: Problems,
    holds: Holds | None = None,
    frames: dict[str, bytes] | None = None,
) -> Express:
    """An express of ``command`` for rotator a (``frames``: others too), its holds told to
    ``holds`` when given (rule 8)."""
    return Express(
        SETTINGS,
        topics=TOPICS,
        frames=frames or {"a": b";"},
        on_problem=problems,
        command=command,
        on_hold=holds.hold if holds else None,
        on_release=holds.release if holds else None,
    )


@contextlib.contextmanager
def up_on_a_fake_clock(
    command: list[str], problems: Problems, holds: Holds, now: list[float]
) -> Iterator[Express]:
    """An express of ``command`` started and up, its holds' clock ``now[0]`` (rule 8's ticks
    read it), stopped at the end."""
    e = express(command, problems, holds)
    e.clock = lambda: now[0]
    e.start(mqtt311=False)
    try:
        wait_until(e.up.is_set, 10, "up")
        yield e
    finally:
        e.stop()


def test_an_express_that_cannot_start_is_said() -> None:
    problems = Problems()
    e = express(["/nonexistent/python"], problems)
    e.start(mqtt311=False)
    wait_until(problems.on, 10, "the problem said")
    assert "could not start" in problems.on()[0] and "stop lane" in problems.on()[0]
    e.stop()


def test_an_express_that_ends_is_said_with_its_exit_code() -> None:
    problems = Problems()
    e = express([sys.executable, "-c", "import sys; sys.exit(3)"], problems)
    e.start(mqtt311=False)
    wait_until(problems.on, 10, "the problem said")
    assert "ended (exit code 3)" in problems.on()[0]
    e.stop()


def test_an_express_that_does_not_give_a_port_back_is_killed_and_the_port_closed() -> None:
    problems = Problems()
    # takes the port, then hangs: holds the socket, reads nothing more, answers nothing
    hung = (
        "import socket, sys, time; s = socket.socket(fileno=int(sys.argv[1])); s.recv(65536); "
        """s.send(b'{"op": "held", "rotator": "a", "n": 1}'); time.sleep(600)"""
    )
    e = express([sys.executable, "-c", hung], problems)
    port = Port()
    e.opened("a", port.w)
    e.start(mqtt311=False)
    wait_until(lambda: "a" in e.held, 10, "it took the port")
    done = threading.Event()
    threading.Thread(target=lambda: (e.closing("a", port.w), done.set()), daemon=True).start()
    wait_until(done.is_set, DROP_WAIT_S + 10, "the closing thread goes on")
    wait_until(problems.on, 10, "the problem said")
    assert "ended" in problems.on()[0]
    e.stop()


def test_no_rotator_of_a_model_that_takes_a_stop_at_any_time_no_express() -> None:
    problems = Problems()
    e = Express(SETTINGS, topics=TOPICS, frames={}, on_problem=problems, command=["false"])
    assert not e.wanted and e.watch("a") is None
    e.start(mqtt311=False)
    assert e._child is None and not problems.said


def test_only_models_that_take_a_stop_frame_at_any_moment_get_the_express() -> None:
    """ModelSpec.stop_anytime (rule 4): not a SatEL (it ignores input while it slews), not a
    SPID (a stop is answered: an extra one would be a reply nobody owes), not a DCU-1 or an
    RT-21 (what they answer to a stop at any moment is not documented)."""
    writes = {name for name, spec in REGISTRY.items() if spec.stop_anytime}
    assert writes == {"rotorez", "rotorcard", *GS232_MODELS, *EASYCOMM_MODELS}


SAYS = (
    "import json, socket, sys\n"
    "s = socket.socket(fileno=int(sys.argv[-1]))\n"
    "s.recv(65536)\n"
    "for word in sys.argv[1:-1]:\n"
    "    s.send(word.encode())\n"
    "s.recv(65536)\n"  # until the bridge closes its end
)


def test_a_refused_connection_is_said_until_the_express_is_up_a_denial_stays() -> None:
    problems = Problems()
    words = [
        {"op": "problem", "text": "refused: not authorised", "until_up": True},
        {"op": "problem", "text": "denied: rotor/a/stop"},
        {"op": "up"},
    ]
    e = express([sys.executable, "-c", SAYS, *map(json.dumps, words)], problems)
    e.start(mqtt311=False)
    wait_until(e.up.is_set, 10, "up")
    wait_until(lambda: len(problems.said) == 2, 10, "both said")
    assert problems.on() == ["stop express: denied: rotor/a/stop"]
    e.stop()


def test_a_port_reopened_before_the_old_one_is_closed_stays_the_expresss() -> None:
    """The old port's closing thread runs late (a busy machine): the new port is already
    open and handed over. Only the old copy is given back; the express keeps the new one."""
    problems = Problems()
    e = Express(SETTINGS, topics=TOPICS, frames={"a": b";"}, on_problem=problems)
    old, new = Port(), Port()
    e.opened("a", old.w)
    e.start(mqtt311=False)
    wait_until(lambda: "a" in e.held, 10, "the old port held")
    e.held_changed.clear()
    e.opened("a", new.w)  # the replugged adapter's port, opened first
    wait_until(e.held_changed.is_set, 10, "the new port held")
    e.closing("a", old.w)  # then the old port's close thread tells it is going
    os.close(old.w)
    os.close(new.w)  # the bridge's copy of the new port; the express's must stay
    try:
        assert "a" in e.held
        with pytest.raises(BlockingIOError):  # a writer is left: the express's copy
            os.read(new.r, 10)
        assert os.read(old.r, 10) == b""  # the old port: no copy left anywhere
    finally:
        e.stop()


def test_a_port_closed_while_the_express_is_still_starting_is_given_back_not_killed() -> None:
    """A slow machine (a Raspberry Pi loading Python): the express is not reading its socket
    yet when a port closes (an unplug, a quick shutdown). That is no hung express: the drop
    waits for it to start, and it stays the rotators' fast stop afterwards."""
    problems = Problems()
    slow_start = (
        f"import sys, time; time.sleep({2 * DROP_WAIT_S}); "
        "from bridge.interfaces.mqtt.express import main; sys.exit(main(sys.argv))"
    )
    e = express([sys.executable, "-c", slow_start], problems)
    port = Port()
    e.opened("a", port.w)
    e.start(mqtt311=False)
    wait_until(lambda: e._sock is not None, 10, "started")
    try:
        e.closing("a", port.w)
        os.close(port.w)
        assert os.read(port.r, 10) == b""  # its copy given back
        assert not problems.on() and not e.ended.is_set()
    finally:
        e.stop()


def test_when_the_bridge_goes_its_ports_are_given_back_before_the_express_disconnects(
    rig: ChildRig,
) -> None:
    """The bridge's process died (its end of the socket closed): the express closes its copies
    of the ports at once, not after its MQTT goodbye (a broker away: seconds), so a bridge
    restarted at once does not find its ports busy (their TIOCEXCL)."""
    port = Port()
    rig.hand("a", 1, port)
    os.close(port.w)  # the bridge's copy went with its process
    rig.mine.close()
    rig.thread.join(slow(5))
    assert os.read(port.r, 10) == b""  # no writer left: the express's copy is closed


def test_a_port_closing_as_the_bridge_stops_is_not_called_a_hung_express(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The express is told to stop while a port's close waits for its copy back: the express
    is gone with its copies, so the close goes on at once, and no kill is logged."""
    problems = Problems()
    # takes the port, never answers a drop, ends on its end of file
    deaf = (
        "import socket, sys; s = socket.socket(fileno=int(sys.argv[1])); s.recv(65536); "
        """socket.recv_fds(s, 65536, 4); s.send(b'{"op": "held", "rotator": "a", "n": 1}')\n"""
        "while s.recv(65536): pass"
    )
    e = express([sys.executable, "-c", deaf], problems)
    port = Port()
    e.opened("a", port.w)
    e.start(mqtt311=False)
    wait_until(lambda: "a" in e.held, 10, "it took the port")
    done = threading.Event()
    closing = threading.Thread(target=lambda: (e.closing("a", port.w), done.set()), daemon=True)
    closing.start()
    wait_until(lambda: 1 in e._dropped, 10, "the close waits for the copy back")
    e.stop()
    wait_until(done.is_set, 10, "the close goes on")
    assert e._child is not None and e._child.returncode == 0  # its end of file, not a kill
    assert not [r for r in caplog.records if "killed" in r.getMessage()]


# -- the parent's side of rule 8, rule 6's restart, a fight said ---------------------------------
ON_SYNC = (  # a fake express: up at once, then what follows for each sync word it is asked
    "import json, socket, sys\n"
    "s = socket.socket(fileno=int(sys.argv[-1]))\n"
    "s.recv(65536)\n"
    's.send(b\'{"op": "up"}\')\n'
    "last = None\n"
    "while True:\n"
    "    word = s.recv(65536)\n"
    "    if not word:\n"
    "        break\n"
    "    word = json.loads(word)\n"
    "    if word.get('op') == 'sync':\n"
)
ANSWERS_LATE = ON_SYNC + (  # answers each sync word when the next is asked for (slow)
    "        if last is not None:\n"
    "            s.send(json.dumps({'op': 'synced', 'n': last}).encode())\n"
    "        last = word['n']\n"
)


class Holds:
    def __init__(self) -> None:
        self.log: list[tuple[str, str, int]] = []
        self.lost: list[tuple[str, int]] = []

    def hold(self, rid: str, n: int) -> None:
        self.log.append(("hold", rid, n))

    def release(self, rid: str, n: int, lost: bool = False) -> None:
        self.log.append(("release", rid, n))
        if lost:  # (by the express's loss: session/stops.py rule 5)
            self.lost.append((rid, n))


def _read_by_the_child(e: Express) -> None:
    """Every request sent read: the next is sent, not answered by one it has not read yet."""
    sock = e._sock
    assert sock is not None
    wait_until(lambda: not express_module._unread(sock.sock), 10, "its requests read")


def test_a_hold_ends_with_the_answer_to_its_own_word_or_with_the_express() -> None:
    problems, holds = Problems(), Holds()
    e = express(
        [sys.executable, "-c", ANSWERS_LATE], problems, holds, frames={"a": b";", "b": b"S\r"}
    )
    e.hold("a")  # no express running: nothing of one can write, no hold
    assert holds.log == []
    e.start(mqtt311=False)
    try:
        wait_until(e.up.is_set, 10, "up")
        e.hold("a")
        _read_by_the_child(e)
        e.hold("b")  # answers word 1: a's hold waits for it, b's for 2
        wait_until(lambda: ("release", "a", 1) in holds.log, 10, "a's hold ended")
        _read_by_the_child(e)
        e.hold("a")  # answers 2: b's hold ends; a's waits for 3
        wait_until(lambda: ("release", "b", 2) in holds.log, 10, "b's hold ended")
        assert [h for h in holds.log if h[0] == "release"] == [
            ("release", "a", 1),
            ("release", "b", 2),
        ]
        child = e._child
        assert child is not None
        child.kill()  # nothing of it can write any more: the last hold ends
        wait_until(lambda: ("release", "a", 3) in holds.log, 10, "a's hold ended by its end")
        assert holds.lost == [("a", 3)]  # (by its end, not its word: what waited is dropped)
    finally:
        e.stop()


ANSWERS_LOST = ON_SYNC + (  # its connection ends with every request unanswered
    "        s.send(json.dumps({'op': 'synced', 'n': word['n'], 'lost': True}).encode())\n"
)


def test_a_hold_ended_by_the_expresss_lost_connection_is_told_as_lost() -> None:
    """An attack pass: a firewall dropped the express's flow alone; the answer its
    connection's end gave looked like its word, and the target held behind the STOP went out
    45 s late. The bridge is told which it was."""
    problems, holds = Problems(), Holds()
    e = express([sys.executable, "-c", ANSWERS_LOST], problems, holds)
    e.start(mqtt311=False)
    try:
        wait_until(e.up.is_set, 10, "up")
        e.hold("a")
        wait_until(lambda: ("release", "a", 1) in holds.log, 10, "a's hold ended")
        assert holds.lost == [("a", 1)]
    finally:
        e.stop()


def test_a_long_hold_is_said_and_the_word_asked_for_again(monkeypatch: pytest.MonkeyPatch) -> None:
    problems, holds, now = Problems(), Holds(), [1000.0]
    with up_on_a_fake_clock([sys.executable, "-c", ANSWERS_LATE], problems, holds, now) as e:
        e.hold("a")
        _read_by_the_child(e)  # (read: no hung express)
        now[0] += 10.0  # the answer does not come: said, and asked for again
        wait_until(lambda: any("not yet answered" in p for p in problems.on()), 10, "said")
        wait_until(lambda: ("release", "a", 1) in holds.log, 10, "the word asked for again")
        wait_until(lambda: not problems.on(), 10, "unsaid once it ended")


UP_AND_HOLDING = (
    "import json, socket, sys\n"
    "s = socket.socket(fileno=int(sys.argv[-1]))\n"
    "s.recv(65536)\n"
    's.send(b\'{"op": "up"}\')\n'
    "while True:\n"
    "    data, fds, _f, _a = socket.recv_fds(s, 65536, 4)\n"
    "    if not data:\n"
    "        break\n"
    "    word = json.loads(data)\n"
    "    if word.get('op') == 'port':\n"
    "        held = {'op': 'held', 'rotator': word['rotator'], 'n': word['n']}\n"
    "        s.send(json.dumps(held).encode())\n"
)


def test_an_express_that_dies_is_said_started_again_and_given_the_ports_again() -> None:
    problems = Problems()
    e = express([sys.executable, "-c", UP_AND_HOLDING], problems)
    port = Port()
    e.opened("a", port.w)
    e.start(mqtt311=False)
    try:
        wait_until(lambda: "a" in e.held, 10, "it holds the port")
        first = e._child
        assert first is not None
        first.kill()
        said = wait_until(lambda: [p for p in problems.texts() if "ended" in p], 10, "its end said")
        assert "started again in" in said[0] and "stop lane" in said[0]
        wait_until(lambda: e.starts == 2 and "a" in e.held, 10, "started again, the port handed")
        assert e._child is not first
        wait_until(lambda: not problems.on(), 10, "unsaid once it is up again")
    finally:
        e.stop()


def test_an_express_that_dies_while_the_bridge_stops_is_not_said_to_start_again() -> None:
    """Killed while the bridge was stopping (a service manager's SIGKILL to the group): the log
    said it was "started again in 1 s", and it was, by a bridge on its way out. Its end is said
    as one while the bridge stops, and nothing is started again."""
    problems = Problems()
    e = express([sys.executable, "-c", UP_AND_HOLDING], problems)
    port = Port()
    e.opened("a", port.w)
    e.start(mqtt311=False)
    try:
        wait_until(lambda: "a" in e.held, 10, "it holds the port")
        e.shutting_down()
        first = e._child
        assert first is not None
        first.kill()
        said = wait_until(lambda: [p for p in problems.texts() if "ended" in p], 10, "its end said")
        assert "as the bridge stops" in said[0] and "started again" not in said[0], said
        assert e.runner is not None
        e.runner.join(slow(10))
        assert not e.runner.is_alive() and e.starts == 1, "started again while the bridge stops"
    finally:
        e.stop()


def test_a_fight_over_its_client_id_is_said_and_unsaid_once_a_connection_lasts() -> None:
    from bridge.interfaces.mqtt.connection import STABLE_S
    from bridge.interfaces.mqtt.express import _Link

    said: list[dict[str, object]] = []
    now = [0.0]
    link = _Link(
        SETTINGS,
        "rfast-shack",
        lambda **word: said.append(word),
        lambda up: None,
        subscriptions=["rotor/a/stop"],
        on_message=lambda *a: None,
        clock=lambda: now[0],
    )
    link._ended(ReasonCode(PacketTypes.DISCONNECT, identifier=0x8E), "taken over", True)
    assert said and "taken over" in str(said[0]["text"]) and "rfast-shack" in str(said[0]["text"])
    link._ended(
        ReasonCode(PacketTypes.DISCONNECT, identifier=0x8E), "taken over", True
    )  # once an episode
    assert len(said) == 1
    link._guard.connected(now[0])
    now[0] += STABLE_S
    link._tick()
    assert said[-1] == {"op": "problem", "text": said[0]["text"], "off": True}


UP_THEN_HUNG = (  # says it is up, then reads nothing more: a hung express
    "import socket, sys, time; s = socket.socket(fileno=int(sys.argv[-1])); s.recv(65536); "
    """s.send(b'{"op": "up"}'); time.sleep(600)"""
)


def _fill(sock: socket.socket) -> None:
    """What requests the express does not read leave behind: its socket full."""
    try:
        while True:
            sock.send(b"{}", socket.MSG_DONTWAIT)
    except (BlockingIOError, TimeoutError):
        pass


@pytest.mark.parametrize("what", ["opened", "closing"])
def test_a_port_told_to_a_hung_express_never_holds_up_a_stop(what: str) -> None:
    """A port opened or closed while a hung express's socket is full: the send to it never
    waits under the express's lock, which every MQTT stop takes (its hold, rule 8) before it
    is put in; the express is killed, and the stop goes on."""
    problems, holds = Problems(), Holds()
    e = express([sys.executable, "-c", UP_THEN_HUNG], problems, holds)
    port = Port()
    if what == "closing":
        e.opened("a", port.w)
    e.start(mqtt311=False)
    try:
        wait_until(e.up.is_set, 10, "up")
        sock = e._sock
        assert sock is not None
        _fill(sock.sock)
        told = threading.Thread(target=getattr(e, what), args=("a", port.w), daemon=True)
        told.start()
        stopped = threading.Event()

        def stop() -> None:  # what halts.py does for an MQTT stop, before it puts the stop in
            e.hold("a")
            stopped.set()

        threading.Thread(target=stop, daemon=True).start()
        wait_until(stopped.is_set, 10, "the stop's hold returned")
        wait_until(lambda: any("ended" in p for p in problems.on()), 10, "the hung one killed")
        told.join(slow(10))
        assert not told.is_alive()
    finally:
        e.stop()


def test_a_hung_express_found_by_a_flood_of_stops_is_killed_and_said_once(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A flood of stops finds a hung express's socket full, each of them until it has died: it
    was killed and said once per stop (32-95 identical ERROR lines in a flood of 40,000)."""
    problems, holds = Problems(), Holds()
    e = express([sys.executable, "-c", UP_THEN_HUNG], problems, holds)
    e.start(mqtt311=False)
    try:
        wait_until(e.up.is_set, 10, "up")
        sock, child = e._sock, e._child
        assert sock is not None and child is not None
        _fill(sock.sock)
        with caplog.at_level(logging.ERROR, logger=express_module.__name__):
            for _ in range(20):
                e.hold("a")  # what halts.py does for each MQTT stop
            wait_until(lambda: child.poll() is not None, 10, "the hung one killed")
        kills = [r for r in caplog.records if "killed" in r.getMessage()]
        assert [r.getMessage() for r in kills] == ["stop express does not read its socket: killed"]
    finally:
        e.stop()


READS_WHEN_TOLD = (  # up, then reads nothing until SIGUSR1; then answers each request it reads
    "import json, signal, socket, sys\n"
    "s = socket.socket(fileno=int(sys.argv[-1]))\n"
    "s.recv(65536)\n"
    "signal.pthread_sigmask(signal.SIG_BLOCK, [signal.SIGUSR1])\n"
    's.send(b\'{"op": "up"}\')\n'
    "signal.sigwait([signal.SIGUSR1])\n"
    "while True:\n"
    "    word = s.recv(65536)\n"
    "    if not word:\n"
    "        break\n"
    "    word = json.loads(word)\n"
    "    s.send(json.dumps({'op': 'synced', 'n': word['n']}).encode())\n"
)


def test_a_flood_of_stops_never_fills_the_socket_of_an_express_that_reads_it_late(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A flood of stops (40,000 in the attack pass) carried out on both connections asked the
    express for a sync word each: a few hundred fill its socket, and an express whose reader
    waited a few dozen milliseconds for its core was killed as hung. A request it has not
    read yet answers for every stop after it: one is sent, and its answer ends every hold."""
    problems, holds = Problems(), Holds()
    e = express([sys.executable, "-c", READS_WHEN_TOLD], problems, holds)
    e.start(mqtt311=False)
    try:
        wait_until(e.up.is_set, 10, "up")
        child = e._child
        assert child is not None
        with caplog.at_level(logging.ERROR, logger=express_module.__name__):
            for _ in range(2000):
                e.hold("a")  # what halts.py does for each MQTT stop
            assert not [r for r in caplog.records if "killed" in r.getMessage()]
            os.kill(child.pid, signal.SIGUSR1)  # it reads now: one request, answered
            wait_until(lambda: ("release", "a", 2000) in holds.log, 10, "every hold ended")
        assert child.poll() is None and e.starts == 1
        assert not [r for r in caplog.records if "killed" in r.getMessage()]
        assert [h for h in holds.log if h[0] == "release"] == [("release", "a", 2000)]
    finally:
        e.stop()


def test_an_express_that_leaves_one_request_unread_is_killed_as_hung(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Requests it has not read stand for the later ones, so a hung express's socket no longer
    fills: a word of the bridge's it leaves unread READ_WAIT_S is the hang; it is killed, and
    its hold ends with it."""
    problems, holds, now = Problems(), Holds(), [1000.0]
    with up_on_a_fake_clock([sys.executable, "-c", UP_THEN_HUNG], problems, holds, now) as e:
        child = e._child
        assert child is not None
        with caplog.at_level(logging.ERROR, logger=express_module.__name__):
            e.hold("a")
            now[0] += READ_WAIT_S  # (the reader looks once a second)
            wait_until(lambda: child.poll() is not None, 10, "the hung one killed")
            wait_until(lambda: ("release", "a", 1) in holds.log, 10, "its hold ended with it")
        kills = [r.getMessage() for r in caplog.records if "killed" in r.getMessage()]
        assert kills == ["stop express does not read its socket (a word unread for 2.0 s): killed"]


def reader_asleep(e: Express) -> threading.Event:
    """Set each time the express's reader judges that nothing waits (rule 1: its next wait has
    no end but a word sent to it); cleared by the test."""
    asleep = threading.Event()
    tick = e._tick

    def watched(*args: Any) -> bool:
        waits = tick(*args)
        if not waits:
            asleep.set()
        return waits

    e._tick = watched  # type: ignore[method-assign]
    return asleep


def test_a_sleeping_reader_is_woken_by_a_hold_and_finds_the_express_hung(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Rule 1: with nothing to look at (the express up, every word read, no hold) the reader
    sleeps until a word is sent to it; the request a hold sends wakes it, and an express that
    leaves it unread READ_WAIT_S is still found hung and killed (rule 8)."""
    problems, holds, now = Problems(), Holds(), [1000.0]
    with up_on_a_fake_clock([sys.executable, "-c", UP_THEN_HUNG], problems, holds, now) as e:
        child = e._child
        assert child is not None
        asleep = reader_asleep(e)
        wait_until(asleep.is_set, 10, "the reader asleep, nothing to look at")
        with caplog.at_level(logging.ERROR, logger=express_module.__name__):
            e.hold("a")
            now[0] += READ_WAIT_S
            wait_until(lambda: child.poll() is not None, 10, "the hung one killed")
            wait_until(lambda: ("release", "a", 1) in holds.log, 10, "its hold ended with it")
        kills = [r.getMessage() for r in caplog.records if "killed" in r.getMessage()]
        assert kills == ["stop express does not read its socket (a word unread for 2.0 s): killed"]


SLOW_START = (  # a host loading Python slowly: reads nothing until SIGUSR1, then is up
    "import signal, socket, sys, time\n"
    "signal.pthread_sigmask(signal.SIG_BLOCK, [signal.SIGUSR1])\n"
    "signal.sigwait([signal.SIGUSR1])\n"
    "s = socket.socket(fileno=int(sys.argv[-1]))\n"
    "s.recv(65536)\n"
    's.send(b\'{"op": "up"}\')\n'
    "time.sleep(600)\n"
)


def test_an_express_slow_to_start_is_said_late_never_killed(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """Rule 6: a start, however long (a Raspberry Pi loading Python from a cold SD card), is said
    late and waited for; the unread word that is a hang (rule 8) is one left by an express that
    has said a word. A kill there restarted it, and killed it again, for ever."""
    monkeypatch.setattr(express_module, "START_WAIT_S", 0.0)  # late at once
    problems = Problems()
    e = express([sys.executable, "-c", SLOW_START], problems)
    now = [1000.0]
    e.clock = lambda: now[0]
    ticks = threading.Semaphore(0)
    tick = e._tick

    def counted(*args: Any) -> bool:
        waits = tick(*args)
        ticks.release()
        return waits

    e._tick = counted  # type: ignore[method-assign]
    e.start(mqtt311=False)
    try:
        wait_until(lambda: e._sock is not None and e._child is not None, 10, "started")
        child = e._child
        assert child is not None
        with caplog.at_level(logging.ERROR, logger=express_module.__name__):
            now[0] += 10 * READ_WAIT_S  # its config word unread for that long
            for _ in range(2):  # the reader looked at it twice since
                assert ticks.acquire(timeout=slow(10)), "the reader did not look"
            assert child.poll() is None and e.starts == 1
            assert problems.on()  # said late (rule 6)
            os.kill(child.pid, signal.SIGUSR1)  # loaded now
            wait_until(e.up.is_set, 10, "up")
        assert e.starts == 1 and child.poll() is None
        assert not [r for r in caplog.records if "killed" in r.getMessage()]
    finally:
        e.stop()


def test_a_request_not_read_yet_answers_only_for_stops_after_the_highest_one_sent() -> None:
    """_Outbox: a request left out is answered by the last one sent, not read yet; never by
    one numbered below another sent before it (two threads carry stops out, in either order:
    the express may have answered the higher one with a word published before this stop)."""
    mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    box = _Outbox(mine, lambda: 0.0)

    def read() -> list[object]:
        theirs.setblocking(False)
        got: list[object] = []
        try:
            while True:
                word = json.loads(theirs.recv(65536))
                got.append(word.get("n", word["op"]))
        except BlockingIOError:
            return got

    try:
        box.ask(1, False)
        box.ask(2, False)  # 1 not read yet: it answers for 2
        box.ask(3, False)
        assert read() == [1]
        assert box.answer(1) == 3
        box.ask(5, False)
        assert read() == [5]
        box.ask(4, False)  # the other thread's, late: sent, but stands for no later one
        box.ask(6, False)
        assert read() == [4, 6]
        assert box.answer(5) == 5  # (nothing left out)
        box.send({"op": "drop"})  # the last word is no request: 7 goes
        box.ask(7, False)
        box.ask(8, True)  # asked again (rule 8's resend): it goes
        assert read() == ["drop", 7, 8]
    finally:
        mine.close()
        theirs.close()


CHATTY = (  # up, then a word every 50 ms (a frame written for each stop of a flood), no answer
    "import socket, sys, time; s = socket.socket(fileno=int(sys.argv[-1])); s.recv(65536); "
    """s.send(b'{"op": "up"}'); s.setblocking(False)\n"""
    "while True:\n"
    """    s.send(b'{"op": "wrote", "rotator": "a", "t": 0}'); time.sleep(0.05)\n"""
    "    try:\n"
    "        s.recv(65536)\n"  # (it reads the bridge's requests: no hung express)
    "    except BlockingIOError:\n"
    "        pass"
)


def test_a_long_hold_is_said_while_the_express_keeps_talking() -> None:
    """Its words coming faster than once a second (a stop flood, each frame said) must not
    keep the reader from looking at the holds: a long one is said and its word asked again."""
    problems, holds, now = Problems(), Holds(), [1000.0]
    with up_on_a_fake_clock([sys.executable, "-c", CHATTY], problems, holds, now) as e:
        e.hold("a")
        _read_by_the_child(e)  # (read: no hung express)
        now[0] += 10.0  # the answer does not come: said all the same
        wait_until(lambda: any("not yet answered" in p for p in problems.on()), 10, "said")


def test_an_express_whose_socket_has_a_high_descriptor_number_is_read() -> None:
    """A bridge with many clients open has descriptors above 1023 (beyond select())."""
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard != resource.RLIM_INFINITY and hard < 1200:
        pytest.skip("no room for 1200 descriptors")
    resource.setrlimit(resource.RLIMIT_NOFILE, (max(soft, 1200), hard))
    r, w = os.pipe()
    taken = [os.dup(r) for _ in range(1100)]
    problems = Problems()
    e = express([sys.executable, "-c", UP_AND_HOLDING], problems)
    try:
        e.start(mqtt311=False)
        wait_until(e.up.is_set, 10, "its words read")
        assert e.starts == 1
    finally:
        e.stop()
        for fd in [*taken, r, w]:
            os.close(fd)
        resource.setrlimit(resource.RLIMIT_NOFILE, (soft, hard))


def test_a_word_the_bridge_cannot_read_ends_that_express_said_and_it_starts_again() -> None:
    """Rule 6 (an attack pass): a word cut at the socket's read (or no JSON at all) killed
    the express's reader with it: no hold was answered again, no target after a stop went
    out, and nothing said so. The child is killed and said to have ended, and started again."""
    problems = Problems()
    words = [json.dumps({"op": "up"}), '{"op": "wrote", "rotator": "a", "operator": "\\ufb']
    e = express([sys.executable, "-c", SAYS, *words], problems)
    e.start(mqtt311=False)
    try:
        wait_until(lambda: any("ended" in t for t in problems.on()), 10, "its end said")
        # started again (RESTART_FIRST_S later), and the reader goes on: its words are read
        wait_until(lambda: e.starts >= 2, 10, "the next child started")
        assert e.runner.is_alive()
    finally:
        e.stop()


def test_a_word_of_another_shape_ends_that_express_said_and_it_starts_again() -> None:
    """Rule 6 (a review): a word of JSON whose fields are not its ``op``'s (a child started
    from a package upgraded under the running bridge names them otherwise) raised in the
    reader, which died as it did on a cut word: no hold answered again, no target after a
    stop went out, nothing said. The child is killed, said to have ended, and started again."""
    problems = Problems()
    words = [json.dumps({"op": "up"}), json.dumps({"op": "wrote", "rotator": "a", "at": 5.0})]
    e = express([sys.executable, "-c", SAYS, *words], problems)
    e.start(mqtt311=False)
    try:
        wait_until(lambda: any("ended" in t for t in problems.on()), 10, "its end said")
        wait_until(lambda: e.starts >= 2, 10, "the next child started")
        assert e.runner.is_alive()
    finally:
        e.stop()
