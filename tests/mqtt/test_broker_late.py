"""A broker that holds messages up (attack 13): the bridge's own heartbeats read back and the
quiet its network thread saw decide whether the broker held it up (heartbeat.py rule 11,
``Echo``, in virtual time: a backlog, a slow link, a quiet bridge never), and while it is late,
an unstamped move read on the main connection is refused and nothing else is (service.py rule
12, with recording rotators).

The real broker frozen and run on: tests/faults/test_attack13_broker_stall_late_target.py."""

from __future__ import annotations

import pytest

from bridge.core.model import Stop, Target
from bridge.interfaces.mqtt.heartbeat import MAX_ECHOES, QUIET_S, UNREAD_S, Echo, Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.mqtt.test_groups import STACK
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator
from tests.support.clock import FakeClock

BEAT_S = 2.0
POLL_S = 1.0  # the network thread's longest wait (paho_client.py rule 2)


class Link:
    """The main connection's network thread on a fake clock, as paho_client.py rule 11 tells the
    echo what it saw: polls that find nothing (``quiet``), reads (``read``: a message, ``back``:
    one of our beats), and beats sent named by their send time as the real ones are."""

    def __init__(self, *, read_back: bool = True) -> None:
        self.clock = FakeClock()
        self.echo = Echo()
        self.echo.connected()
        self.read()  # the CONNACK
        if read_back:  # one beat read back: the broker lets them through
            self.back(self.send())

    def send(self) -> bytes:
        payload = f"{self.clock():.3f}".encode()
        self.echo.sent(payload, self.clock())
        return payload

    def quiet(self, seconds: float) -> None:
        """Nothing comes for ``seconds``: the thread's polls wait it out, POLL_S at most each."""
        end = self.clock() + seconds
        while self.clock() < end:
            self.clock.t = min(end, self.clock() + POLL_S)
            self.echo.quiet(self.clock())

    def busy(self, seconds: float, step_s: float = 0.01) -> None:
        """A backlog for ``seconds``: every poll finds bytes, read one message after another."""
        end = self.clock() + seconds
        while self.clock() < end:
            self.clock.t = min(end, self.clock() + step_s)
            self.read()

    def read(self, payload: bytes | None = None) -> bool:
        """A read that finds bytes (one of our beats, ``payload``, or anything else); whether
        it was a beat of ours."""
        self.echo.reading(self.clock())
        ours = payload is not None and self.echo.back(payload, self.clock())
        self.echo.read(self.clock())
        return ours

    def back(self, payload: bytes) -> bool:
        return self.read(payload)

    def late(self) -> float | None:
        return self.echo.late(self.clock())


def test_beats_that_come_back_at_once_never_make_the_broker_late() -> None:
    link = Link()
    for _ in range(100):
        beat = link.send()
        link.quiet(0.002)  # a round trip
        assert link.back(beat)
        assert link.late() is None
        link.quiet(BEAT_S + 0.9)  # (a beat goes up to a second late: paho's loop)
        assert link.late() is None


@pytest.mark.parametrize("rtt_s", [0.5, 1.5, 2.5, QUIET_S - 0.1])
def test_a_steady_slow_link_is_never_late(rtt_s: float) -> None:
    """Every round trip the same, up to just under QUIET_S, the beats due every BEAT_S and sent
    up to a poll later (2 to 2.9 s apart): each comes back in time, some in a pipeline."""
    link = Link()
    gaps = [BEAT_S, BEAT_S + 0.9, BEAT_S + 0.45]
    sends = [link.clock() + sum(gaps[i % 3] for i in range(k)) for k in range(60)]
    echoes = {round(t + rtt_s, 6): f"{t:.3f}".encode() for t in sends}
    events = sorted([(t, "send") for t in sends] + [(t, "echo") for t in echoes])
    for t, what in events:
        link.quiet(t - link.clock())
        if what == "send":
            link.send()
        else:
            assert link.back(echoes[t])
        assert link.late() is None


def test_a_backlog_reads_the_beats_late_but_shows_no_quiet_and_is_never_late() -> None:
    """The burst of 10,000 targets: the main connection seconds behind, its own beats read
    many seconds after they went (the reverted design's refusal of the newest target)."""
    link = Link()
    out = []
    for _ in range(10):  # 20 s behind: a beat every period, each read back 10 s later
        out.append(link.send())
        link.busy(BEAT_S)
        if len(out) > 5:
            assert link.back(out.pop(0))
        assert link.late() is None
    while out:
        link.busy(BEAT_S)
        assert link.back(out.pop(0))
        assert link.late() is None
    assert not link.echo.unread(link.clock())


def test_quiet_through_quiet_s_with_a_beat_out_is_a_hold_until_a_later_beat_is_back() -> None:
    link = Link()
    first = link.send()
    link.quiet(QUIET_S - 0.5)
    assert link.late() is None  # (not yet)
    held = [link.send()]  # (a beat period later, held with the first)
    link.quiet(0.5)
    assert link.late() == QUIET_S  # the stall, while it lasts (said on B/bridge/info)
    for _ in range(3):  # the broker frozen 10 s in all: every beat meanwhile held with it
        link.quiet(BEAT_S)
        held.append(link.send())
    link.quiet(10.0 - link.clock() + 100.0)
    link.read()  # it runs on: a held target, read first
    assert link.late() == pytest.approx(10.0)  # judged before the target was handled
    assert link.echo.returning  # (a beat goes at once)
    assert link.back(first)
    for payload in held:  # those held with it: still late
        assert link.back(payload)
        assert link.late() is not None
    link.clock.t += 0.01
    after = link.send()
    assert not link.echo.returning
    link.read()  # (more the broker held)
    assert link.late() is not None
    link.clock.t += 0.01
    assert link.back(after)  # a beat sent after the hold is back: the broker is quick again
    assert link.late() is None


def test_held_beats_read_before_the_held_target_do_not_end_the_hold() -> None:
    """mosquitto may pass on the bridge's beats it held before the target it held: the hold is
    judged at the first read after the quiet, and only a beat sent after it ends it."""
    link = Link()
    beat = link.send()
    link.quiet(10.0)
    assert link.back(beat)  # the first bytes after the quiet: our own beat, held 10 s
    assert link.late() is not None
    link.read()  # then the target
    assert link.late() is not None


def test_quiet_without_a_beat_out_is_no_hold() -> None:
    """The heartbeat off (or every beat back): an idle broker is silent, and holds nothing."""
    link = Link()
    link.quiet(60.0)
    assert link.late() is None
    link.read()
    assert link.late() is None
    assert not link.echo.returning


def test_quiet_before_a_beat_went_out_counts_for_nothing() -> None:
    """Only the part of the quiet through which a beat was out: 10 s idle, then a beat out
    for less than QUIET_S before the next read."""
    link = Link()
    link.quiet(10.0)
    link.send()
    link.quiet(QUIET_S - 0.5)
    link.read()
    assert link.late() is None


def test_a_hold_is_judged_on_the_quiet_seen_not_on_the_time_between_reads() -> None:
    """A network thread that did not poll (the host stalled the bridge itself) saw no quiet:
    what it reads afterwards is no hold (docs/architecture.md rule 15)."""
    link = Link()
    link.send()
    link.clock.t += 10.0  # no poll returned meanwhile
    link.read()
    assert link.late() is None


def test_a_beat_of_another_bridge_or_a_forger_is_no_echo_and_ends_nothing() -> None:
    link = Link()
    link.send()
    link.quiet(QUIET_S + 1.0)
    assert not link.back(b"1700000000.123")  # not ours; the read itself ends the quiet
    assert link.late() is not None
    link.echo.sent(b"1700000000.124", link.clock())  # (ours, after the hold)
    link.read()
    assert link.late() is not None


def test_beats_sent_before_one_that_came_back_are_lost_not_out_for_ever() -> None:
    link = Link()
    link.send()  # lost (QoS 0)
    link.quiet(BEAT_S)
    beat = link.send()
    link.quiet(0.01)
    assert link.back(beat)
    link.quiet(60.0)
    assert link.late() is None
    link.read()
    assert link.late() is None


def test_a_connection_none_of_whose_beats_come_back_is_never_late_and_says_so_once() -> None:
    """An ACL that denies reading the heartbeat topic: the broker is not called late for ever
    (every move refused); that the beats are not read back is known after UNREAD_S of quiet
    seen with one out."""
    link = Link(read_back=False)
    for _ in range(int(UNREAD_S / BEAT_S)):
        link.send()
        link.quiet(BEAT_S)
        assert link.late() is None
        link.read()  # (a command, now and then)
        assert link.late() is None
    assert not link.echo.unread(link.clock())
    link.quiet(0.5)
    assert link.echo.unread(link.clock())
    assert link.late() is None
    late_one = link.send()
    link.quiet(QUIET_S + 1.0)
    assert link.back(late_one)  # one came back after all (a stall, not an ACL)
    assert not link.echo.unread(link.clock())
    assert link.late() is not None  # and the broker had held it: judged from now on


def test_a_start_up_backlog_longer_than_unread_s_is_no_acl() -> None:
    """Review 57: a start-up reading tens of thousands of retained topics reads its first beats
    back late; no quiet was seen, so they are behind the backlog, not unread."""
    link = Link(read_back=False)
    first = link.send()
    for _ in range(int(3 * UNREAD_S / BEAT_S)):
        link.busy(BEAT_S)
        link.send()
        assert not link.echo.unread(link.clock())
    assert link.back(first)
    assert link.late() is None


def test_a_new_connection_forgets_the_last_ones_beats_and_holds() -> None:
    link = Link()
    out = link.send()
    link.quiet(QUIET_S + 1.0)
    link.read()
    assert link.late() is not None
    link.echo.connected()
    assert link.late() is None
    assert not link.echo.returning
    assert not link.back(out)  # (the last connection's: not this one's)
    assert link.late() is None
    link.quiet(QUIET_S + 1.0)  # nothing out on this one yet
    link.read()
    assert link.late() is None


def test_a_broker_frozen_longer_than_the_beats_kept_still_shows_one_out_through_the_quiet() -> None:
    link = Link()
    for _ in range(MAX_ECHOES + 10):
        link.send()
        link.quiet(BEAT_S)
    link.read()
    held = link.late()
    assert held is not None and held > QUIET_S


def test_a_hold_before_any_read_of_the_connection_is_said_from_its_beat_on() -> None:
    """(Nothing read yet on the connection: the quiet counts from the beat that was out.)"""
    clock, echo = FakeClock(), Echo()
    echo.connected()
    echo.sent(b"100.000", clock())
    clock.t += 5.0
    echo.quiet(clock())
    echo.reading(clock())
    assert echo.late(clock()) is None  # (no beat of the connection back yet: not judged)
    assert echo.back(b"100.000", clock())
    assert echo.late(clock()) == 5.0  # the hold stands until a beat sent after it is back


# -- the service (rule 12) ------------------------------------------------------------------------
class Broker:
    def __init__(self) -> None:
        self.held_s: float | None = None

    def late(self) -> float | None:
        return self.held_s


def late_service() -> tuple[Broker, MqttService, RecordingRotator, RecordingRotator]:
    broker = Broker()
    roots = {"upper": "rotor/upper", "lower": "rotor/lower"}
    svc = MqttService(
        Topics("rotor", roots, {"stack": "rotor/stack"}),
        RecordingPublisher(),
        wall=lambda: NOW_UNIX,
        broker_late=broker.late,
    )
    upper, lower = RecordingRotator("upper", "rotorez"), RecordingRotator("lower", "rotorez")
    svc.attach(upper)
    svc.attach(lower)
    svc.attach_group(STACK)
    return broker, svc, upper, lower


MOVES = [
    ("target", b"200"),
    ("target", b"JN58td"),
    ("target", b'{"path": "long"}'),
    ("target", b'{"call": "DL1ABC"}'),
    ("preset", b"EU"),
    ("park", b"PARK"),
    ("nudge", b"10"),
    ("track", b"moon"),
    ("follow", b"wsjtx"),
]


def test_while_the_broker_is_late_every_unstamped_move_is_refused_saying_why() -> None:
    broker, svc, upper, _lower = late_service()
    broker.held_s = 10.4
    for leaf, payload in MOVES:
        svc.on_message(f"rotor/upper/{leaf}", payload, False)
    assert [c[0] for c in upper.calls] == ["refused"] * len(MOVES)
    assert all("held this up: it passed nothing on for 10 s" in str(c[1]) for c in upper.calls)
    assert all("send it again" in str(c[1]) for c in upper.calls)


def test_while_the_broker_is_late_stop_lock_options_and_offs_go_through() -> None:
    """Nothing that turns no rotor is refused: stop and lock ON never are (docs/architecture.md
    rule 11), a lock OFF lets only a later move go (judged then), tracking or following OFF
    stop a rotor."""
    broker, svc, upper, _lower = late_service()
    broker.held_s = 10.4
    svc.on_message("rotor/upper/stop", b"", False)
    svc.on_message("rotor/upper/lock", b"ON", False)
    svc.on_message("rotor/upper/lock", b"OFF", False)
    svc.on_message("rotor/upper/track", b"OFF", False)
    svc.on_message("rotor/upper/follow", b"OFF", False)
    kinds = [c[0] for c in upper.calls]
    assert kinds == ["submit", "lock", "lock", "track", "follow"]
    assert isinstance(upper.calls[0][1], Stop)


def test_a_stamped_move_is_refused_too_while_the_broker_is_late() -> None:
    """service.py rule 12 (review 61): a stamped move read in the window is refused though its
    stamp would pass: let through, it stood over a newer unstamped move refused beside it."""
    broker, svc, upper, _lower = late_service()
    broker.held_s = 10.4
    stamp = Stamp.of(NOW_UNIX - 0.2, 5.0)  # sent 0.2 s ago, by its stamp
    svc.on_message("rotor/upper/target", b"200", False, stamp=stamp)
    assert [c[0] for c in upper.calls] == ["refused"]
    assert "held this up" in str(upper.calls[0][1])
    broker.held_s = None  # a beat sent after the hold is back: the next stamped move goes
    svc.on_message("rotor/upper/target", b"200", False, stamp=stamp)
    assert [c[0] for c in upper.calls] == ["refused", "submit"]


def test_a_group_target_is_refused_for_every_member_while_the_broker_is_late() -> None:
    broker, svc, upper, lower = late_service()
    broker.held_s = 7.0
    svc.on_message("rotor/stack/target", b"120", False)
    assert upper.calls[-1][0] == "audited" and lower.calls[-1][0] == "audited"
    assert not any(c[0] == "submit" for c in (*upper.calls, *lower.calls))
    assert "held this up" in str(upper.calls[-1][1])


def test_once_the_broker_is_quick_again_the_next_move_turns_the_rotor() -> None:
    broker, svc, upper, _lower = late_service()
    broker.held_s = 10.4
    svc.on_message("rotor/upper/target", b"200", False)
    broker.held_s = None
    svc.on_message("rotor/upper/target", b"200", False)
    assert [c[0] for c in upper.calls] == ["refused", "submit"]
    assert upper.calls[1][1] == Target(200.0, None, upper.calls[1][1].source)  # type: ignore[union-attr]
