"""Attack pass 5 on interfaces/mqtt/remote.py rule 8 / heartbeat.py rule 10 (the floor): "a
move never before the latest stamp a halt on one of its ``after`` topics (its rotator's stop
and lock) went out with". The floor is there for the client's own ``S`` then ``P`` read in
one go; but it is kept per rotator, not per front end or connection, so it lifts *any* move
over *any* halt the remote sent for that rotator, whoever sent it.

Sequence: Gpredict's rotctld ``P 200 0`` reaches the remote at t=8 s, its connection's thread
asleep over its budget (or the computer busy), so no look counts it yet; at t=9 s the
operator presses STOP in PstRotator (the remote's logger port), which goes out stamped 9 s;
the rotctld thread wakes, its look (after the STOP: the halt count includes it, the fence
does not refuse) dates the P's bytes at 8 s (tcplines.py rule 9: right), and the link lifts
its stamp to the STOP's, 9 s. The station compares the two stamps directly (service.py rule
9: older only if stamped *before* the halt): the P turns the rotor after the operator's STOP,
though it was seen before it. Stamped at its seen time, it would be refused.
"""

from __future__ import annotations

import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from bridge.core.errors import RefusalCode, Refused
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.remote import HALT_READERS, RemoteLink
from bridge.settings.mqtt import MqttSettings
from tests.remote.test_late_commands import Paho
from tests.support.clock import FakeClock


def _sent(props: object) -> float:
    stamp = Stamp.of_properties(list(getattr(props, "UserProperty", None) or []))
    assert stamp is not None
    sent = stamp.sent_unix()
    assert sent is not None
    return sent


def _link() -> tuple[FakeClock, RemoteLink, Paho]:
    """A remote's link on a fake clock, connected, its broker a recorder that acknowledges."""
    clock = FakeClock()
    link = RemoteLink(
        MqttSettings(),
        "remote-test",
        [],
        lambda topic, payload, retain: None,
        last_word=lambda topic, payload: topic.endswith("/stop"),
        heartbeat="rotor/bridge/heartbeat",
        clock=clock,
        ack_wait_s=0.0,
    )
    fake = Paho(link, ReasonCode(PacketTypes.PUBACK, identifier=0))
    link._client = fake  # type: ignore[assignment]  # noqa: SLF001
    link.connected.set()
    return clock, link, fake


def _floor_alone(link: RemoteLink) -> None:
    """The remote's own refusal of a move seen before a halt it sent, or before another
    reader's halt was read (rule 8, review 30), set aside until the next halt: the stamp the
    floor alone gives, what the station judges."""
    link._halt_latest.clear()  # noqa: SLF001
    link._halt_read.clear()  # noqa: SLF001


def test_a_move_seen_before_another_front_ends_stop_is_not_lifted_to_its_stamp() -> None:
    clock, link, fake = _link()
    link.station_clock.heard(1_700_000_000.0 + clock.t)
    t0 = clock.t
    clock.t = t0 + 10.0
    link.station_clock.heard(1_700_000_000.0 + clock.t)  # (a live beat now)
    # PstRotator's STOP, seen at t0 + 9
    link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=t0 + 9.0)
    # Gpredict's P, seen at t0 + 8 (before the STOP), read after it
    after = ("rotor/stop", "rotor/lock")
    with pytest.raises(Refused) as refused:  # (review 30: refused here, seen before it)
        link.send("rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=t0 + 8.0, after=after)
    assert refused.value.code is RefusalCode.STALE
    assert len(fake.published) == 1
    _floor_alone(link)
    link.send("rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=t0 + 8.0, after=after)
    (stop_topic, stop_props), (move_topic, move_props) = fake.published
    assert stop_topic == "rotor/stop" and move_topic == "rotor/target"
    assert _sent(move_props) < _sent(stop_props), (
        f"the move seen 1 s before the STOP went out stamped {_sent(move_props):.3f}, the "
        f"STOP's own {_sent(stop_props):.3f}: the station takes it for not older and turns "
        "the rotor after the STOP (the floor lifts a move over any front end's halt)"
    )


def test_a_move_is_lifted_to_its_own_readers_halt_alone() -> None:
    """The fix (remote.py rule 8): the floor is the last halt the move's own reader (its
    connection, pty or logger port and sender) read: that reader's move is never stamped
    before it, another reader's move keeps its own seen time."""
    clock, link, fake = _link()
    t0 = clock.t
    clock.t = t0 + 10.0
    link.station_clock.heard(1_700_000_000.0 + clock.t)
    after = ("rotor/stop", "rotor/lock")
    link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=t0 + 9.0, reader="rotctld 1")
    _floor_alone(link)
    link.send("rotor/target", '{"azimuth":1}', "DL1ABC", 5, seen_s=t0 + 8.0, after=after)
    link.send(
        "rotor/target", '{"azimuth":2}', "DL1ABC", 5, seen_s=t0 + 8.0, after=after, reader="pst"
    )
    link.send(
        "rotor/target",
        '{"azimuth":3}',
        "DL1ABC",
        5,
        seen_s=t0 + 8.0,
        after=after,
        reader="rotctld 1",
    )
    stop, unknown, other, own = (_sent(props) for _topic, props in fake.published)
    assert unknown < stop and other < stop, "lifted to another reader's STOP"
    assert own >= stop, "the reader's own STOP left its move stamped before it"


def test_the_sources_whose_halts_lift_their_moves_are_bounded() -> None:
    """Rule 8's bound: a program that opens a connection per STOP (each its own reader) does
    not grow the link's record without end; the newest readers' halts still lift their own
    moves, and a forgotten reader's move keeps its seen time (refused at worst, never lifted
    over a halt that is not its own)."""
    clock, link, fake = _link()
    t0 = clock.t
    clock.t = t0 + 10.0
    link.station_clock.heard(1_700_000_000.0 + clock.t)
    after = ("rotor/stop", "rotor/lock")
    for n in range(HALT_READERS * 4):
        link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=t0 + 9.0, reader=f"flood {n}")
    assert len(link._halt_stamps) <= HALT_READERS  # noqa: SLF001
    fake.published.clear()
    _floor_alone(link)
    newest, first = f"flood {HALT_READERS * 4 - 1}", "flood 0"
    for reader in (newest, first):
        link.send(
            "rotor/target",
            '{"azimuth":1}',
            "DL1ABC",
            5,
            seen_s=t0 + 8.0,
            after=after,
            reader=reader,
        )
    own, forgotten = (_sent(props) for _topic, props in fake.published)
    assert own >= 1_700_000_000.0 + 9.0 - 0.001, "the newest reader's STOP no longer lifts its move"
    assert forgotten < own, "a forgotten reader's move was lifted"
