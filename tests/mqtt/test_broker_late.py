"""A broker that holds messages up (attack 13): the bridge's own heartbeats read back decide
whether it is late (heartbeat.py rule 11, ``Echo``, in virtual time), and while it is, an
unstamped move read on the main connection is refused and nothing else is (service.py rule 12,
with recording rotators).

The real broker frozen and run on: tests/faults/test_attack13_broker_stall_late_target.py."""

from __future__ import annotations

import pytest

from bridge.core.model import Stop, Target
from bridge.interfaces.mqtt.heartbeat import LATE_S, MAX_ECHOES, UNREAD_S, Echo, Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.mqtt.test_groups import STACK
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator
from tests.support.clock import FakeClock

BEAT_S = 2.0


class Beats:
    """The connection's side of the echo: beats sent every BEAT_S on a fake clock, named by
    their send time as the real ones are (their payload)."""

    def __init__(self) -> None:
        self.clock = FakeClock()
        self.echo = Echo()
        self.echo.sent(b"0", self.clock())  # one beat read back: the broker lets it through
        self.echo.back(b"0", self.clock())

    def send(self) -> bytes:
        payload = f"{self.clock():.3f}".encode()
        self.echo.sent(payload, self.clock())
        return payload

    def back(self, payload: bytes) -> bool:
        return self.echo.back(payload, self.clock())

    def late(self) -> float | None:
        return self.echo.late(self.clock())

    def elapse(self, seconds: float) -> None:
        self.clock.t += seconds


def test_beats_that_come_back_at_once_never_make_the_broker_late() -> None:
    b = Beats()
    for _ in range(100):
        assert b.back(b.send())
        assert b.late() is None
        b.elapse(BEAT_S)


def test_a_beat_out_longer_than_late_s_makes_the_broker_late_while_it_stays_out() -> None:
    b = Beats()
    first = b.send()
    b.elapse(LATE_S)
    assert b.late() is None  # (just within it)
    b.elapse(0.5)
    assert b.late() == LATE_S + 0.5
    held = []
    for _ in range(4):  # the broker frozen 10 s: every beat sent meanwhile held with the first
        b.elapse(BEAT_S)
        held.append(b.send())
    assert b.late() == LATE_S + 8.5
    b.elapse(0.01)
    assert b.back(first)  # it runs on: the first back, 10.5 s after it went
    assert b.late() == pytest.approx(LATE_S + 8.51)
    assert b.echo.returning  # (a beat goes at once)
    for payload in held:  # the others held with it went before the return: still late
        assert b.back(payload)
        assert b.late() is not None
    b.elapse(0.01)
    after = b.send()
    assert not b.echo.returning
    assert b.late() is not None
    b.elapse(0.01)
    assert b.back(after)  # a beat sent after the return is back: the broker is quick again
    assert b.late() is None


def test_a_late_beat_that_comes_back_keeps_the_broker_late_until_a_later_one_is_back() -> None:
    """A beat out less than LATE_S, but sent before the late one came back, does not end it:
    what the broker held may still come behind it."""
    b = Beats()
    early = b.send()
    b.elapse(1.0)
    soon = b.send()
    b.elapse(LATE_S)
    assert b.back(early)  # out 3 s
    assert b.late() == LATE_S + 1.0
    assert b.back(soon)  # out 2 s: in time, but sent before that return
    assert b.late() == LATE_S + 1.0


def test_a_beat_of_another_bridge_or_a_forger_is_no_echo_and_changes_nothing() -> None:
    b = Beats()
    b.send()
    b.elapse(LATE_S + 1.0)
    assert not b.back(b"1700000000.123")  # not ours
    assert b.late() == LATE_S + 1.0


def test_beats_sent_before_one_that_came_back_are_lost_not_late_for_ever() -> None:
    b = Beats()
    b.send()  # lost (QoS 0)
    b.elapse(BEAT_S)
    assert b.back(b.send())
    b.elapse(60.0)
    assert b.late() is None


def test_a_connection_none_of_whose_beats_come_back_is_never_late_and_says_so_once() -> None:
    """An ACL that denies reading the heartbeat topic: the broker is not called late for ever
    (every move refused); that the beats are not read back is known after UNREAD_S."""
    clock, echo = FakeClock(), Echo()
    for _ in range(int(UNREAD_S / BEAT_S)):
        echo.sent(f"{clock():.3f}".encode(), clock())
        clock.t += BEAT_S
        assert echo.late(clock()) is None
    assert not echo.unread(clock())
    clock.t += 0.5
    assert echo.unread(clock())
    assert echo.late(clock()) is None
    late_one = f"{clock():.3f}".encode()
    echo.sent(late_one, clock())
    clock.t += LATE_S + 1.0
    assert echo.back(late_one, clock())  # one came back after all (a stall, not an ACL)
    assert not echo.unread(clock())
    assert echo.late(clock()) == LATE_S + 1.0  # and it was late: judged from now on


def test_a_new_connection_forgets_the_last_ones_beats() -> None:
    b = Beats()
    out = b.send()
    b.elapse(LATE_S + 1.0)
    assert b.late() is not None
    b.echo.connected()
    assert b.late() is None
    assert not b.back(out)  # (the last connection's: not this one's)
    assert b.late() is None


def test_a_broker_frozen_longer_than_the_beats_kept_still_shows_one_out_too_long() -> None:
    b = Beats()
    for _ in range(MAX_ECHOES + 10):
        b.send()
        b.elapse(BEAT_S)
    held = b.late()
    assert held is not None and held > LATE_S


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
    assert all("held up the bridge's messages for 10 s" in str(c[1]) for c in upper.calls)
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


def test_a_stamped_move_is_judged_by_its_own_send_time_not_by_the_broker() -> None:
    broker, svc, upper, _lower = late_service()
    broker.held_s = 10.4
    stamp = Stamp.of(NOW_UNIX - 0.2, 5.0)  # sent 0.2 s ago, by its stamp
    svc.on_message("rotor/upper/target", b"200", False, stamp=stamp)
    assert [c[0] for c in upper.calls] == ["submit"]


def test_a_group_target_is_refused_for_every_member_while_the_broker_is_late() -> None:
    broker, svc, upper, lower = late_service()
    broker.held_s = 7.0
    svc.on_message("rotor/stack/target", b"120", False)
    assert upper.calls[-1][0] == "audited" and lower.calls[-1][0] == "audited"
    assert not any(c[0] == "submit" for c in (*upper.calls, *lower.calls))
    assert "held up" in str(upper.calls[-1][1])


def test_once_the_broker_is_quick_again_the_next_move_turns_the_rotor() -> None:
    broker, svc, upper, _lower = late_service()
    broker.held_s = 10.4
    svc.on_message("rotor/upper/target", b"200", False)
    broker.held_s = None
    svc.on_message("rotor/upper/target", b"200", False)
    assert [c[0] for c in upper.calls] == ["refused", "submit"]
    assert upper.calls[1][1] == Target(200.0, None, upper.calls[1][1].source)  # type: ignore[union-attr]
