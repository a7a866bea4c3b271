"""A command from the remote that a link held up, a station that is dead or locked: in virtual
time (fake clocks, a stand-in link, the station's service on a recording rotator). The wiring
on a real mosquitto with a link that stalls is tests/remote/test_stalled_link.py.

What the operator would see: rotctld's answer (``RPRT 0`` only when the command is on its way
and the station will take it), and at the station, whether the rotator was asked to turn."""

from __future__ import annotations

import socket
import sys
import threading
import time
from typing import Any

import paho.mqtt.client as paho_client
import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties
from paho.mqtt.reasoncodes import ReasonCode

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import SentAt, Source, Stop, Target
from bridge.interfaces.mqtt.client import MqttClient
from bridge.interfaces.mqtt.heartbeat import (
    AHEAD_S,
    CLOCK_WINDOW_S,
    MAX_BUCKETS,
    MAX_PROPERTIES_BYTES,
    SILENT_S,
    UNREAD_PROPERTIES,
    Beat,
    Stamp,
    StationClock,
    StationTime,
    beat_payload,
    parse_beat,
)
from bridge.interfaces.mqtt.remote import RemoteLink
from bridge.interfaces.mqtt.topics import StationTopics
from bridge.interfaces.rotctld.server import RotctldSession
from bridge.remote.rotator import Info, RemoteRotator, StationView
from bridge.settings.mqtt import MqttSettings
from tests.mqtt.test_service import NOW_UNIX, service
from tests.support.clock import FakeClock
from tests.support.remote import Link
from tests.support.waiting import slow

STATION = StationTopics("rotor")
T = STATION.rotator(None)
INFO = b'{"name":"tower","model":"rotorez","azimuth_range":[0,360]}'


def remote(clock: FakeClock, link: Link) -> tuple[RemoteRotator, StationView]:
    view = StationView(clock)
    view.put(STATION.bridge_state, b"online", replayed=True)  # what a restored broker holds
    view.put(T.availability, b"online", replayed=True)
    view.put(
        T.status,
        b'{"bearing":42.0,"state":"idle","connected":true,"available":true}',
        replayed=True,
    )
    return RemoteRotator("tower", T, STATION, Info.parse(INFO), view, link, "DL1ABC", 5), view


def rotctld(rot: RemoteRotator, line: bytes) -> bytes:
    return RotctldSession(rot).feed(line)[0]  # type: ignore[arg-type]


# -- the station's heartbeat: a dead station is not read as alive -----------------------------
def test_a_station_never_heard_is_offline_though_the_broker_says_online() -> None:
    """A broker restored from its file holds ``online`` and the last bearing of a bridge that
    died with it: the remote answered ``p`` with that bearing and ``RPRT 0`` to moves."""
    clock, link = FakeClock(), Link()
    rot, view = remote(clock, link)
    assert rotctld(rot, b"p\n") == b"RPRT -5\n"
    assert rotctld(rot, b"P 200 0\n") == b"RPRT -5\n"
    assert link.sent == []
    assert rotctld(rot, b"S\n") == b"RPRT -5\n"  # a stop goes, said to be undelivered
    view.put(STATION.bridge_heartbeat, beat_payload(NOW_UNIX).encode())  # a live bridge
    assert rotctld(rot, b"p\n") == b"42.00\n0.00\n"
    assert rotctld(rot, b"P 200 0\n") == b"RPRT 0\n"
    assert link.sent == [(T.stop, "stop"), (T.target, '{"azimuth":200.0}')]


def test_a_station_gone_silent_turns_offline_after_three_missed_beats() -> None:
    clock, link = FakeClock(), Link()
    rot, view = remote(clock, link)
    view.put(STATION.bridge_heartbeat, b"1700000000.000")
    clock.t += SILENT_S
    assert rotctld(rot, b"p\n") == b"42.00\n0.00\n"
    clock.t += 0.1
    assert rotctld(rot, b"p\n") == b"RPRT -5\n"
    assert rotctld(rot, b"P 10 0\n") == b"RPRT -5\n"
    view.put(STATION.bridge_heartbeat, b"1700000000.000", replayed=True)  # no news of anyone
    assert rotctld(rot, b"p\n") == b"RPRT -5\n"


def test_the_station_beats_every_heartbeat_s() -> None:
    beat, t = Beat(2.0), 100.0
    due = []
    for _ in range(50):
        due.append(beat.due(t))
        t += 0.25
    assert due.count(True) == 7 and due[0] and due[8]  # at 0, 2, 4, ... 12 s
    assert parse_beat(beat_payload(1_700_000_000.5).encode()) == 1_700_000_000.5
    for junk in (b"", b"nan", b"-1", b"inf", b"\xff", b"1e400"):
        with pytest.raises(ValueError):
            parse_beat(junk)


# -- the lock: refused at once, as for the lease ----------------------------------------------
def test_a_move_while_the_station_is_locked_is_refused_at_once_and_a_stop_still_goes() -> None:
    """The remote answered ``RPRT 0`` and the station refused in silence on its R/error."""
    clock, link = FakeClock(), Link()
    rot, view = remote(clock, link)
    view.put(STATION.bridge_heartbeat, b"1700000000.000")
    view.put(T.lock_state, b"ON", replayed=True)
    assert rotctld(rot, b"P 200 0\n") == b"RPRT -9\n"
    with pytest.raises(Refused) as refused:
        rot.submit(Target(200, None, Source.ROTCTLD))
    assert refused.value.code is RefusalCode.LOCKED
    assert "safety lock is ON" in refused.value.message
    assert rotctld(rot, b"S\n") == b"RPRT 0\n"
    assert link.sent == [(T.stop, "stop")]
    view.put(T.lock_state, b"OFF")
    assert rotctld(rot, b"P 200 0\n") == b"RPRT 0\n"


# -- the send time: reckoned on the station's clock, judged by the station ---------------------
def test_the_reckoned_station_clock_is_never_ahead_whatever_the_skew() -> None:
    """The remote's clock an hour off the station's: the stamp follows the station's clock,
    late by the fastest trip of a heartbeat, never early."""
    mono = FakeClock(50.0)
    station_clock = StationClock(mono)
    assert station_clock.now_unix() is None  # never heard: no stamp
    station_now = 1_700_000_000.0
    for trip_s in (0.30, 0.05, 0.80):  # each beat's trip from the station's clock to us
        station_clock.heard(station_now - trip_s)
        mono.t += 2.0
        station_now += 2.0
    reckoned = station_clock.now_unix()
    assert reckoned is not None and station_now - 0.05 == pytest.approx(reckoned)
    mono.t += CLOCK_WINDOW_S + 1  # the beats forgotten: no reckoning
    assert station_clock.now_unix() is None


def test_a_command_a_link_held_up_is_refused_by_the_station_and_a_stop_is_not() -> None:
    """The link stalled 15 s with the target in it: stamped with its send time, the station
    refuses it on arrival (R/error), and does not refuse a stop held as long."""
    svc, _, rots = service({"tower": "rotorez"})
    sent = Stamp.of(NOW_UNIX - 15.0, 5)
    svc.on_message("rotor/target", b"200", False, "DL1ABC", stamp=sent)
    svc.on_message("rotor/park", b"park", False, "DL1ABC", stamp=sent)
    svc.on_message("rotor/stop", b"stop", False, "DL1ABC", stamp=sent)
    svc.on_message("rotor/lock", b"ON", False, "DL1ABC", stamp=sent)
    calls = rots["tower"].calls
    assert [c[0] for c in calls] == ["refused", "refused", "submit", "lock"]
    assert "sent 15.0 s ago, older than its 5 s expiry" in calls[0][1]
    stop = calls[2][1]
    # heartbeat.py rule 8: a stamp older than its expiry times nothing: when it came counts
    assert isinstance(stop, Stop) and stop == Stop()


def test_a_halt_is_timed_by_its_stamp_only_when_the_stamp_would_pass_on_a_move() -> None:
    """heartbeat.py rule 8: a STOP two seconds old, inside its expiry, is timed by its stamp;
    one stamped by a clock five minutes slow (however long its expiry), unreadable or against
    another station process is carried out and timed when it came (its ``sent_s`` none), so
    that a target a held-up link lets go a second later, stamped a second before it came, is
    refused as older."""
    svc, _, rots = service({"tower": "rotorez"}, station="abc")
    fresh = Stamp.of(NOW_UNIX - 2.0, 5, "abc")
    svc.on_message("rotor/stop", b"stop", False, "DL1ABC", stamp=fresh)
    for stamp in (
        Stamp.of(NOW_UNIX - 300.0, 5, "abc"),
        Stamp.of(NOW_UNIX - 300.0, 3600, "abc"),  # (fresh by its expiry: past the most)
        Stamp("yesterday", "5", "abc"),
        Stamp.of(NOW_UNIX - 2.0, 5, "old"),
    ):
        svc.on_message("rotor/stop", b"stop", False, "DL1ABC", stamp=stamp)
    stops = [c[1] for c in rots["tower"].calls]
    assert all(isinstance(stop, Stop) for stop in stops) and len(stops) == 5
    assert stops[0].sent_s == pytest.approx(time.monotonic() - 2.0, abs=1.0)
    assert [stop.sent_s for stop in stops[1:]] == [None, None, None, None]
    rots["tower"].halted_s = time.monotonic()  # runtime/rotator.py ``_halted``: when it came
    svc.on_message("rotor/target", b"200", False, "DL1ABC", stamp=Stamp.of(NOW_UNIX - 1, 5, "abc"))
    assert rots["tower"].calls[-1][0] == "refused"
    assert "sent before the last STOP" in rots["tower"].calls[-1][1]


def test_a_move_stamped_before_the_rotators_last_halt_is_refused_and_one_after_is_not() -> None:
    """heartbeat.py rule 8: the rotator's last STOP or lock ON came a second ago (from any
    interface); a target stamped two seconds ago, inside its expiry, is refused, one stamped
    half a second ago and one without a stamp are carried out; a halt is never refused."""
    svc, _, rots = service({"tower": "rotorez"})
    rots["tower"].halted_s = time.monotonic() - 1.0
    svc.on_message("rotor/target", b"200", False, "DL1ABC", stamp=Stamp.of(NOW_UNIX - 2.0, 5))
    svc.on_message("rotor/lock", b"OFF", False, "DL1ABC", stamp=Stamp.of(NOW_UNIX - 2.0, 5))
    svc.on_message("rotor/target", b"120", False, "DL1ABC", stamp=Stamp.of(NOW_UNIX - 0.5, 5))
    svc.on_message("rotor/target", b"90", False, "DL1ABC")
    svc.on_message("rotor/stop", b"stop", False, "DL1ABC", stamp=Stamp.of(NOW_UNIX - 2.0, 5))
    calls = rots["tower"].calls
    assert [c[0] for c in calls] == ["refused", "refused", "submit", "submit", "submit"]
    for refused in calls[:2]:
        assert "sent before the last STOP or lock ON" in str(refused[1])


@pytest.mark.parametrize(
    ("stamp", "refused"),
    [
        (Stamp.of(NOW_UNIX - 4.9, 5), None),
        (Stamp.of(NOW_UNIX - 5.1, 5), "older than its 5 s expiry"),
        (Stamp.of(NOW_UNIX + AHEAD_S - 0.1, 5), None),
        (Stamp.of(NOW_UNIX + AHEAD_S + 0.1, 5), "ahead of this station's clock"),
        (Stamp("yesterday", "5"), "cannot be read"),
        (Stamp(str(NOW_UNIX), None), "cannot be read"),
        (Stamp(str(NOW_UNIX), "nan"), "cannot be read"),
        (Stamp(str(NOW_UNIX), "-1"), "cannot be read"),
        (Stamp("-1e308", "5"), "sent 1e+308 s ago, older than its 5 s expiry"),  # (no 300 digits)
        (Stamp(str(NOW_UNIX + 2e6), "5"), "stamped 2e+06 s ahead of"),
        (None, None),  # a dashboard's command: the broker's expiry only
    ],
)
def test_the_station_judges_the_stamp_on_its_own_clock(
    stamp: Stamp | None, refused: str | None
) -> None:
    svc, _, rots = service({"tower": "rotorez"})
    svc.on_message("rotor/target", b"200", False, "DL1ABC", stamp=stamp)
    (call,) = rots["tower"].calls
    if refused is None:
        assert call[0] == "submit"
    else:
        assert call[0] == "refused" and refused in call[1]


def test_the_station_clock_never_goes_back_and_judges_stamps_by_their_true_age() -> None:
    """heartbeat.py rule 6: the station's wall clock set back 10 s after a beat; its clock goes
    on from where it was, so a stamp reckoned from that beat is judged by its true age, however
    long ago the step was; set forward, the clock follows at once."""
    mono, wall = FakeClock(100.0), FakeClock(1_700_000_000.0)
    station = StationTime(wall, mono)
    assert station.now_unix() == 1_700_000_000.0  # the beat: the wall clock, until a step
    mono.t += 1.0
    wall.t += 1.0 - 10.0  # a second later, the wall clock set back 10 s
    held = Stamp.of(1_700_000_001.0 - 12.0, 5)  # held up 12 s: 2 s old by the stepped clock
    fresh = Stamp.of(1_700_000_001.0 - 0.2, 5)  # reckoned from the beat before the step
    assert held.judge(wall()) is None  # (the wall clock alone would carry it out)
    assert "sent 12.0 s ago" in (held.judge(station.now_unix()) or "")
    assert fresh.judge(station.now_unix()) is None  # not "ahead"
    mono.t += 600.0  # ten minutes on (beats all along): the step is not forgotten
    wall.t += 600.0
    assert station.now_unix() == pytest.approx(wall() + 10.0)
    long_held = Stamp.of(1_700_000_001.0 + 600.0 - 125.0, 5)  # held up 125 s
    assert "sent 125.0 s ago" in (long_held.judge(station.now_unix()) or "")
    wall.t += 30.0  # set forward 30 s: followed at once
    assert station.now_unix() == pytest.approx(wall())


def test_a_command_stamped_against_the_station_before_it_restarted_is_refused() -> None:
    """heartbeat.py rule 7: the station's wall clock set back 10 s, then its bridge restarted
    (its clock starts from the lower wall clock). A target the remote stamped from the old
    process's beats and the link held up 12 s reads 2 s old by the new clock: refused for the
    process it names, not carried out. One the new process's beats stamped is carried out;
    one naming no process (an older remote, another client that stamps) is judged by its age."""
    svc, _, rots = service({"tower": "rotorez"}, station="b2")
    held = Stamp.of(NOW_UNIX - 2.0, 5, "a1")
    svc.on_message("rotor/target", b"200", False, "DL1ABC", stamp=held)
    svc.on_message("rotor/target", b"120", False, "DL1ABC", stamp=Stamp.of(NOW_UNIX, 5, "b2"))
    svc.on_message("rotor/target", b"90", False, "DL1ABC", stamp=Stamp.of(NOW_UNIX, 5))
    svc.on_message("rotor/stop", b"stop", False, "DL1ABC", stamp=held)
    calls = rots["tower"].calls
    assert [c[0] for c in calls] == ["refused", "submit", "submit", "submit"]
    assert "before it restarted: not carried out; send it again" in calls[0][1]
    assert calls[3][1] == Stop()  # a stop is never refused


def test_a_lock_off_on_the_stop_lane_stamped_against_the_old_process_is_refused() -> None:
    """service.py rule 9 on the stop lane too: its lock OFF is judged as the main connection's."""
    svc, pub, rots = service({"tower": "rotorez"}, station="b2")
    pub.up = pub.hears = False  # the main connection is down: the lane carries out a lock OFF
    svc.on_lane_message("rotor/lock", b"OFF", False, "DL1ABC", Stamp.of(NOW_UNIX, 5, "a1"))
    assert [c[0] for c in rots["tower"].calls] == ["refused"]
    assert "before it restarted" in str(rots["tower"].calls[0][1])
    svc.on_lane_message("rotor/lock", b"OFF", False, "DL1ABC", Stamp.of(NOW_UNIX, 5, "b2"))
    assert [c[:2] for c in rots["tower"].calls[1:]] == [("lock", False)]


def test_the_remote_forgets_its_reckoning_when_the_beats_name_another_station_process() -> None:
    """heartbeat.py rule 7 on the remote: the old process's beats reckoned the station's clock
    10 s ahead of the new process's (its wall clock was set back before the restart). At the
    first beat of the new process the old reckoning is gone: the stamp follows the new clock
    at once (not "ahead" for a minute) and names the new process."""
    mono = FakeClock(50.0)
    clock = StationClock(mono)
    old_station = 1_700_000_010.0
    for _ in range(5):
        clock.heard(old_station - 0.05, "a1")
        mono.t += 2.0
        old_station += 2.0
    before = clock.stamp(5)
    assert before is not None and before.station == "a1"
    assert float(before.sent) == pytest.approx(old_station - 0.05)
    new_station = old_station - 10.0  # the restarted bridge: its clock 10 s behind the old one
    clock.heard(new_station - 0.05, "b2")
    after = clock.stamp(5)
    assert after is not None and after.station == "b2"
    assert float(after.sent) == pytest.approx(new_station - 0.05)
    assert after.judge(new_station, "b2") is None  # fresh, not "ahead of this station's clock"
    clock.heard(new_station + 2.0, None)  # an older bridge (no name) beats now: forgotten too
    assert clock.stamp(5) == Stamp.of(new_station + 2.0, 5, "")  # named: no name
    mono.t += 2.0
    clock.heard(new_station + 4.0, None)  # the same nameless process: learnt on, not forgotten
    assert len(clock._offsets) == 2


def test_a_move_reckoned_from_nameless_beats_is_refused_by_a_station_that_names_itself() -> None:
    """heartbeat.py rule 7: the remote reckoned the station's clock from beats that named no
    process (the station's bridge spoke MQTT 3.1.1, or was an older one); the station's wall
    clock was set back 10 s and its bridge restarted, upgraded or under MQTT 5. A target sent
    just before the restart and held up 12 s on the link (5 s expiry) reads 2 s old by the
    new process's clock: it must not turn the rotor, as one naming the old process would not.
    One stamped from the new process's own beats goes through."""
    mono = FakeClock(50.0)
    clock = StationClock(mono)
    clock.heard(NOW_UNIX + 10.0 - 12.0, None)  # the old process's clock, 10 s ahead of the new
    held = clock.stamp(5)
    assert held is not None
    svc, _, rots = service({"tower": "rotorez"}, station="b2")
    svc.on_message("rotor/target", b"200", False, "DL1ABC", stamp=held)
    clock.heard(NOW_UNIX, "b2")  # the new process's first beat
    svc.on_message("rotor/target", b"120", False, "DL1ABC", stamp=clock.stamp(5))
    calls = rots["tower"].calls
    assert [c[0] for c in calls] == ["refused", "submit"]
    assert "before it restarted: not carried out; send it again" in calls[0][1]


def test_the_link_stamps_with_the_process_the_heartbeats_name() -> None:
    """remote.py rule 8: a live heartbeat's user property ``station`` goes into the stamp of
    every command sent from its reckoning; a retained beat says nothing."""
    link, paho = link_on(ReasonCode(PacketTypes.PUBACK, identifier=0))
    beat = paho_message("rotor/bridge/heartbeat", b"1700000100.000", [("station", "b2")])
    link._on_message(None, None, beat)
    replayed = paho_message("rotor/bridge/heartbeat", b"1700000200.000", [("station", "zz")])
    replayed.retain = True
    link._on_message(None, None, replayed)
    link.send("rotor/target", '{"azimuth":200}', "DL1ABC", 5)
    ((_, props),) = paho.published
    assert props.UserProperty == [
        ("operator", "DL1ABC"),
        ("sent", "1700000100.000"),
        ("expiry", "5"),
        ("station", "b2"),
    ]


def test_the_stamp_travels_as_user_properties_and_reads_back() -> None:
    stamp = Stamp.of(1_700_000_000.1234, 5)
    pairs = [("operator", "DL1ABC"), *stamp.properties()]
    assert pairs[1:] == [("sent", "1700000000.123"), ("expiry", "5")]
    assert Stamp.of_properties(pairs) == stamp
    assert Stamp.of_properties([("operator", "DL1ABC")]) is None
    named = Stamp.of(1_700_000_000.0, 5, "b2")  # heartbeat.py rule 7
    assert named.properties()[2:] == [("station", "b2")]
    assert Stamp.of_properties([("operator", "DL1ABC"), *named.properties()]) == named
    assert Stamp.of_properties([("station", "b2")]) is None  # a name alone is no stamp


# -- the remote's link: answered only once the broker has it ----------------------------------
class Info_:
    def __init__(self, mid: int) -> None:
        self.mid, self.rc = mid, 0


class Paho:
    """paho's client as RemoteLink.send uses it; ``ack`` says what the broker answers at once
    (None: nothing, the link stalls)."""

    def __init__(self, link: RemoteLink, ack: ReasonCode | None) -> None:
        self.link, self.ack = link, ack
        self.published: list[tuple[str, Any]] = []
        self.ours, self.broker = socket.socketpair()

    def publish(self, topic: str, payload: Any, qos: int, retain: bool, properties: Any) -> Info_:
        mid = len(self.published) + 1
        self.published.append((topic, properties))
        if self.ack is not None:
            self.link._on_publish(None, None, mid, self.ack, None)
        return Info_(mid)

    def socket(self) -> socket.socket:
        return self.ours

    def drop_out_messages(self) -> list[Any]:
        return []


def paho_message(
    topic: str, payload: bytes, pairs: list[tuple[str, str]]
) -> paho_client.MQTTMessage:
    msg = paho_client.MQTTMessage(topic=topic.encode())
    msg.payload = payload
    msg.properties = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
    msg.properties.UserProperty = pairs
    return msg


def link_on(ack: ReasonCode | None) -> tuple[RemoteLink, Paho]:
    link = RemoteLink(
        MqttSettings(),
        "remote-test",
        [],
        lambda topic, payload, retain: None,
        last_word=lambda topic, payload: topic.endswith("/stop"),
        heartbeat="rotor/bridge/heartbeat",
        clock=FakeClock(),
        ack_wait_s=0.0,  # the broker's answer is there at once, or never
    )
    fake = Paho(link, ack)
    link._client = fake  # type: ignore[assignment]
    link.connected.set()
    link.station_clock.heard(1_700_000_000.0)
    return link, fake


def test_a_command_the_broker_acknowledged_is_sent_stamped_on_the_station_clock() -> None:
    link, paho = link_on(ReasonCode(PacketTypes.PUBACK, identifier=0))
    link.send("rotor/target", '{"azimuth":200}', "DL1ABC", 5)
    ((topic, props),) = paho.published
    assert props.UserProperty == [
        ("operator", "DL1ABC"),
        ("sent", "1700000000.000"),
        ("expiry", "5"),
        ("station", ""),  # heartbeat.py rule 7: its beats named no process
    ]
    assert props.MessageExpiryInterval == 5 and link.up and link.resets == 0


def test_a_stop_is_stamped_when_the_station_clock_is_reckoned() -> None:
    """interfaces/mqtt/remote.py rule 8 (heartbeat.py rule 8): with a reckoning, a STOP carries
    its send time, so that the station times it by that, not by its arrival: a move sent right
    after it is not older than it however long the link's trip. Its expiry as any command's."""
    link, paho = link_on(ReasonCode(PacketTypes.PUBACK, identifier=0))
    link.send("rotor/stop", "stop", "DL1ABC", 5)
    ((topic, props),) = paho.published
    assert topic == "rotor/stop" and props.UserProperty == [
        ("operator", "DL1ABC"),
        ("sent", "1700000000.000"),
        ("expiry", "5"),
        ("station", ""),
    ]


def test_a_stop_kept_for_the_stations_return_is_stamped_with_the_beat_that_heard_it() -> None:
    """Rule 6 and rule 8: a STOP sent while the station's bridge was not heard goes again at
    its first live beat, stamped with that beat's time (the station's clock has passed it; no
    reckoning is made from the beat before the halts kept go), its operator and expiry kept."""
    link, paho = link_on(ReasonCode(PacketTypes.PUBACK, identifier=0))
    link.station_clock.forget()
    link.send("rotor/stop", "stop", "DL1ABC", 5, until_heard=True)
    assert paho.published[-1][1].UserProperty == [("operator", "DL1ABC")]  # no reckoning
    beat = paho_message("rotor/bridge/heartbeat", b"1700000123.500", [("station", "b2")])
    link._on_message(None, None, beat)
    topic, props = paho.published[-1]
    assert topic == "rotor/stop" and len(paho.published) == 2
    assert props.UserProperty == [
        ("operator", "DL1ABC"),
        ("sent", "1700000123.500"),
        ("expiry", "5"),
        ("station", "b2"),
    ]
    assert props.MessageExpiryInterval == 5


def test_no_puback_in_time_refuses_the_command_and_resets_the_stalled_connection() -> None:
    """The link stalls: paho took the command and the broker says nothing. The client hears a
    refusal (rotctld RPRT -6 once the link is down), not RPRT 0, and the connection is shut so
    nothing of it reaches the broker when the link recovers."""
    link, paho = link_on(None)
    with pytest.raises(Refused) as refused:
        link.send("rotor/target", '{"azimuth":200}', "DL1ABC", 5)
    assert refused.value.code is RefusalCode.OFFLINE
    assert "did not acknowledge it within" in refused.value.message
    assert not link.up and link.resets == 1
    paho.broker.settimeout(slow(5))
    assert paho.broker.recv(10) == b""  # the connection's end, for paho's loop to read
    with pytest.raises(Refused) as again:  # refused at once until paho has connected again
        link.send("rotor/target", '{"azimuth":100}', "DL1ABC", 5)
    assert again.value.message == "not connected to the station's broker"
    assert len(paho.published) == 1


def test_a_stop_pressed_while_a_stalled_link_is_reset_goes_first_on_reconnect() -> None:
    """The link stalls and is reset; the rotor still turns to its last target. Every STOP the
    operator presses meanwhile is answered truthfully (not delivered yet: rotctld RPRT -6,
    "kept and sent first on reconnect"), and one of them reaches the station first thing on
    the next connection, with its expiry counted from then; a move pressed meanwhile never
    goes, a lock ON does (a halt too)."""
    link, paho = link_on(None)
    with pytest.raises(Refused):
        link.send("rotor/target", '{"azimuth":200}', "DL1ABC", 5)
    assert not link.up
    for _ in range(3):  # the operator presses STOP again and again through the stall
        with pytest.raises(Refused) as kept:
            link.send("rotor/stop", "stop", "DL1ABC", 5)
        assert kept.value.code is RefusalCode.OFFLINE
        assert "kept and sent first on reconnect" in kept.value.message
    with pytest.raises(Refused) as refused:
        link.send("rotor/target", '{"azimuth":100}', "DL1ABC", 5)
    assert "kept" not in refused.value.message
    with pytest.raises(Refused):
        link.send("rotor/lock", "OFF", "DL1ABC", 5)  # not a halt: refused, never sent later
    assert len(paho.published) == 1  # nothing went into the dead connection
    paho.ack = ReasonCode(PacketTypes.PUBACK, identifier=0)
    link._closed(True, ReasonCode(PacketTypes.DISCONNECT, identifier=0))  # paho reads the reset
    link._opened(None)  # the link recovered: paho connected again
    link.station_clock.heard(1_700_000_000.0)  # and the station is heard again
    link.send("rotor/target", '{"azimuth":300}', "DL1ABC", 5)
    # the stop first on the new connection, once more before anything later (as at the first
    # heartbeat: interfaces/mqtt/remote.py rule 6), then the move asked after it
    published = [topic for topic, _ in paho.published]
    assert published == ["rotor/target", "rotor/stop", "rotor/stop", "rotor/target"]
    _, held = paho.published[1]
    assert held.MessageExpiryInterval == 5  # counted by the broker from this connection on
    assert held.UserProperty == [("operator", "DL1ABC")]


def test_a_stop_through_rotctld_while_the_broker_is_away_says_so_and_is_kept() -> None:
    """rotctld's answer for a stop that could not go now is an error (RPRT -6, not RPRT 0):
    the rotor may still turn; the stop goes first when the broker is back."""
    link, paho = link_on(ReasonCode(PacketTypes.PUBACK, identifier=0))
    link.connected.clear()  # the broker is away
    clock = FakeClock()
    rot, _view = remote(clock, link)  # type: ignore[arg-type]
    assert rotctld(rot, b"S\n") == b"RPRT -6\n"
    assert paho.published == []
    link._opened(None)
    assert [topic for topic, _ in paho.published] == [T.stop]


def test_a_puback_with_a_failure_is_a_refusal_naming_the_acl() -> None:
    link, _ = link_on(ReasonCode(PacketTypes.PUBACK, "Not authorized"))
    with pytest.raises(Refused) as refused:
        link.send("rotor/target", '{"azimuth":200}', "DL1ABC", 5)
    assert "refused it (Not authorized)" in refused.value.message
    assert link.up and link.resets == 0


def test_without_a_heartbeat_only_a_stop_goes_unstamped() -> None:
    link, paho = link_on(ReasonCode(PacketTypes.PUBACK, identifier=0))
    link.station_clock.forget()
    with pytest.raises(Refused) as refused:
        link.send("rotor/target", '{"azimuth":200}', "DL1ABC", 5)
    assert "not heard" in refused.value.message
    link.send("rotor/stop", "stop", "DL1ABC", 5)
    ((topic, props),) = paho.published
    assert topic == "rotor/stop" and props.UserProperty == [("operator", "DL1ABC")]


def test_a_flood_on_the_heartbeat_topic_never_keeps_a_stop_or_a_move_from_going() -> None:
    """Anyone may publish on the heartbeat topic, as fast as they like, on paho's thread while
    the operator's commands are sent on another: every stop and every move still goes out
    (none fails on the reckoning), stamped with the best of the beats."""
    link, paho = link_on(ReasonCode(PacketTypes.PUBACK, identifier=0))
    flooding = threading.Event()
    flooding.set()

    def flood() -> None:
        while flooding.is_set():
            link.station_clock.heard(1_699_999_999.0)

    before = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # threads switch all the time: a race shows at once
    flooder = threading.Thread(target=flood, daemon=True)
    flooder.start()
    try:
        for _ in range(100):
            link.send("rotor/stop", "stop", "DL1ABC", 5)
            link.send("rotor/target", '{"azimuth":200}', "DL1ABC", 5)
    finally:
        flooding.clear()
        flooder.join()
        sys.setswitchinterval(before)
    assert [topic for topic, _ in paho.published] == ["rotor/stop", "rotor/target"] * 100
    stamped = [p.UserProperty for t, p in paho.published if t == "rotor/target"]
    assert all(("sent", "1700000000.000") in props for props in stamped)
    assert len(link.station_clock._offsets) <= MAX_BUCKETS  # a minute of beats, no more


# -- the station's side of the heartbeat: its main connection beats while it is the bridge ----
@pytest.mark.parametrize(
    ("protocol", "named"),
    [("auto", [("station", "b2")]), ("5", [("station", "b2")]), ("3.1.1", None)],
)
def test_the_station_beats_from_its_connection_only_while_connected_and_not_refused(
    protocol: str, named: list[tuple[str, str]] | None
) -> None:
    """Each beat names this process (heartbeat.py rule 7) where MQTT 5 can: not under 3.1.1."""
    clock = FakeClock()
    client = MqttClient(
        MqttSettings(protocol=protocol),  # type: ignore[arg-type]
        will_topic="rotor/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        heartbeat="rotor/bridge/heartbeat",
        clock=clock,
        wall=lambda: 1_700_000_000.25,
        station="b2",
    )
    beats: list[tuple[str, bytes, int, list[tuple[str, str]] | None]] = []

    def publish(topic: str, payload: bytes, qos: int, properties: Any) -> None:
        beats.append((topic, payload, qos, getattr(properties, "UserProperty", None)))

    client._client.publish = publish  # type: ignore[assignment,method-assign]
    client._tick()  # not connected (or its first look still runs): nothing
    client.connected.set()
    for _ in range(9):  # paho's loop, a round every half second
        client._tick()
        clock.t += 0.5
    beat = ("rotor/bridge/heartbeat", b"1700000000.250", 0, named)
    assert beats == [beat] * 3  # at 0, 2 and 4 s
    client.refused = "another bridge runs on rotor"
    clock.t += 10
    client._tick()
    assert len(beats) == 3


def test_a_move_whose_check_fails_under_the_send_lock_never_reaches_paho() -> None:
    """remote.py rule 9: the check a move is sent with is asked under the send lock, right
    before paho is handed the command (another thread's stop holds that lock meanwhile)."""
    link, paho = link_on(ReasonCode(PacketTypes.PUBACK, identifier=0))
    held: list[bool] = []

    def check() -> None:
        held.append(link._send_lock.locked())
        raise Refused(RefusalCode.STALE, "a STOP went out after it was asked")

    with pytest.raises(Refused) as refused:
        link.send("rotor/target", '{"azimuth":200}', "DL1ABC", 5, check)
    assert refused.value.code is RefusalCode.STALE
    assert held == [True] and paho.published == []
    link.send("rotor/target", '{"azimuth":100}', "DL1ABC", 5, lambda: None)
    assert [topic for topic, _ in paho.published] == ["rotor/target"]


def test_a_move_stamped_in_the_same_millisecond_as_the_stop_before_it_is_carried_out(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """heartbeat.py rule 8: a logger on the remote's rotctld sends ``S`` then ``P`` at once;
    both are stamped ``.3f`` in the same millisecond. The station maps each stamp onto its
    steady clock when it comes, through its wall clock; the wall clock drifting a microsecond
    from the steady one between the two (NTP's slew, a float's last bit at 1.7e9 s: about
    half of all such pairs, measured) must not make the target look older than its STOP."""
    import bridge.interfaces.mqtt.service as service_module

    mono, wall = FakeClock(100.0), FakeClock(NOW_UNIX)
    fake_time = type("T", (), {"monotonic": staticmethod(mono), "time": staticmethod(wall)})
    monkeypatch.setattr(service_module, "time", fake_time)
    svc, _, rots = service({"tower": "rotorez"})
    svc._stamp_clock = wall  # (the station's wall clock, as ``wall=`` gives it)
    sent = Stamp.of(NOW_UNIX - 0.05, 5)  # the one millisecond both were sent in
    svc.on_message("rotor/stop", b"stop", False, "DL1ABC", stamp=sent)
    stop = rots["tower"].calls[-1][1]
    assert isinstance(stop, Stop) and isinstance(stop.sent_s, SentAt)
    rots["tower"].halted_s = min(mono(), stop.sent_s)  # runtime/rotator.py ``_halted``,
    rots["tower"].halted_unix = stop.sent_s.unix  # and the stamp it kept (service.py rule 9)
    mono.t += 0.001
    wall.t += 0.001 + 1e-6  # the wall clock a microsecond ahead over that millisecond
    svc.on_message("rotor/target", b"200", False, "DL1ABC", stamp=sent)
    assert [c[0] for c in rots["tower"].calls] == ["submit", "submit"]


def test_a_stamp_is_never_earlier_than_the_one_before_when_the_best_beat_leaves_the_window() -> (
    None
):
    """heartbeat.py rule 8: the reckoning is the best (fastest) beat's in CLOCK_WINDOW_S; when
    that beat leaves the window it drops by the trips' spread (20 ms then, 500 ms now: a link
    grown busy). A STOP stamped just before and a target 0.1 s later just after: the target
    stamped 0.38 s before the STOP, and the station refused it as sent before that STOP."""
    mono = FakeClock(50.0)
    station_clock = StationClock(mono)
    station_now = 1_700_000_000.0
    station_clock.heard(station_now - 0.02)  # a fast beat
    for _ in range(int(CLOCK_WINDOW_S) - 1):
        mono.t += 1.0
        station_now += 1.0
        station_clock.heard(station_now - 0.5)  # slow ones since
    mono.t += 0.95
    stop = station_clock.stamp(5)
    mono.t += 0.1  # the fast beat leaves the window
    target = station_clock.stamp(5)
    assert stop is not None and target is not None
    assert float(target.sent) >= float(stop.sent)


@pytest.mark.parametrize(
    "pairs",
    [
        [("SENT", str(NOW_UNIX - 600)), ("EXPIRY", "5")],
        [("Sent", str(NOW_UNIX - 600)), ("expiry", "5")],
        [("sent", str(NOW_UNIX)), ("Expiry", "5")],  # (its expiry unread: refused all the same)
    ],
)
def test_a_stamp_named_in_other_letters_refuses_a_move_and_says_how_to_name_it(
    pairs: list[tuple[str, str]],
) -> None:
    """heartbeat.py rule 5: MQTT's names are case-sensitive; a flow that meant a stamp (here
    ten minutes old) had its target carried out however late, and nothing said. A STOP so
    stamped is carried out as ever."""
    stamp = Stamp.of_properties(pairs)
    assert stamp is not None
    svc, _, rots = service({"tower": "rotorez"})
    svc.on_message("rotor/target", b"200", False, "DL1ABC", stamp=stamp)
    svc.on_message("rotor/stop", b"stop", False, "DL1ABC", stamp=stamp)
    refusal, stop = rots["tower"].calls
    assert refusal[0] == "refused", refusal
    assert "is no stamp: the names are 'sent' and 'expiry', in small letters" in refusal[1]
    assert stop[0] == "submit" and isinstance(stop[1], Stop)


@pytest.mark.parametrize(
    "pairs",
    [
        [(UNREAD_PROPERTIES, "100013")],
        [("sent", str(NOW_UNIX)), ("expiry", "5"), (UNREAD_PROPERTIES, "100013")],
    ],
)
def test_properties_the_bridge_did_not_read_refuse_a_move_and_leave_a_stop_as_ever(
    pairs: list[tuple[str, str]],
) -> None:
    """heartbeat.py rule 9: a message whose properties were too long to read (paho_client.py
    rule 10) comes with their size alone; a move so sent is refused saying why, a STOP and a
    lock ON are carried out."""
    stamp = Stamp.of_properties(pairs)
    assert stamp is not None
    svc, _, rots = service({"tower": "rotorez"})
    svc.on_message("rotor/target", b"200", False, None, stamp=stamp)
    svc.on_message("rotor/stop", b"stop", False, None, stamp=stamp)
    svc.on_message("rotor/lock", b"ON", False, None, stamp=stamp)
    refusal, stop, lock = rots["tower"].calls
    assert refusal[0] == "refused", refusal
    assert refusal[1] == (
        f"its MQTT 5 properties take 100013 bytes, more than the {MAX_PROPERTIES_BYTES} the "
        "bridge reads (a stamp and an operator's name take some hundred): not carried out"
    )
    assert stop[0] == "submit" and isinstance(stop[1], Stop)
    assert lock[:2] == ("lock", True), lock


def test_a_move_stamped_as_the_stop_before_it_is_carried_out_when_its_thread_loses_the_cpu(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Review 24: the remote stamps ``P`` read with its own ``S`` exactly as that ``S``
    (heartbeat.py rule 10), and the station put both stamps on its steady clock with two
    clock readings each: one millisecond lost between the readings for the target (a GIL
    switch, a loaded Raspberry Pi) made it a millisecond older than its STOP, past the grain:
    refused while the client got RPRT 0 for both. The station now compares the move's stamp
    with the stamp the halt kept (core/model.py ``SentAt``) directly, on one clock: taken."""
    import bridge.interfaces.mqtt.service as service_module

    mono, wall = FakeClock(100.0), FakeClock(NOW_UNIX)
    fake_time = type("T", (), {"monotonic": staticmethod(mono), "time": staticmethod(wall)})
    monkeypatch.setattr(service_module, "time", fake_time)
    svc, _, rots = service({"tower": "rotorez"})
    svc._stamp_clock = wall  # (the station's wall clock, as ``wall=`` gives it)
    sent = Stamp.of(NOW_UNIX - 0.05, 5)  # the S's stamp, and the P's, clamped to it (``after``)
    svc.on_message("rotor/stop", b"stop", False, "DL1ABC", stamp=sent)
    stop = rots["tower"].calls[-1][1]
    assert isinstance(stop, Stop) and isinstance(stop.sent_s, SentAt)
    rots["tower"].halted_s = min(mono(), stop.sent_s)  # runtime/rotator.py ``_halted``,
    rots["tower"].halted_unix = stop.sent_s.unix  # and the stamp it kept
    mono.t += 0.003
    wall.t += 0.003
    reads = {"n": 0}

    def wall_after_a_lost_millisecond() -> float:
        reads["n"] += 1
        if reads["n"] == 2:  # a second reading for the target: 1 ms off the CPU before it
            mono.t += 0.001
            wall.t += 0.001
        return wall()

    svc._stamp_clock = wall_after_a_lost_millisecond
    svc.on_message("rotor/target", b"200", False, "DL1ABC", stamp=sent)
    assert [c[0] for c in rots["tower"].calls] == ["submit", "submit"], rots["tower"].calls[-1]
    older = Stamp.of(NOW_UNIX - 0.051, 5)  # (a millisecond before the STOP's stamp: older)
    svc.on_message("rotor/target", b"210", False, "DL1ABC", stamp=older)
    assert rots["tower"].calls[-1][0] == "refused"
    assert "sent before the last STOP" in str(rots["tower"].calls[-1][1])


def test_a_move_is_stamped_when_it_was_seen_never_before_its_rotators_last_halt() -> None:
    """heartbeat.py rule 10: ``seen_s`` backdates the stamp by the time since (the station's
    clock then, as the beats reckon it now), floored to its millisecond; ``after``, a halt's
    stamp of the same station process, is the earliest it may say; the next stamp sent now
    is not set back by it."""
    mono = FakeClock(100.0)
    station_clock = StationClock(mono)
    station_clock.heard(1_700_000_000.0, "A")
    mono.t += 2.0
    now = station_clock.stamp(5)
    assert now == Stamp.of(1_700_000_002.0, 5, "A")
    seen = station_clock.stamp(5, seen_s=mono.t - 1.5)
    assert seen == Stamp.of(1_700_000_000.5, 5, "A")
    halt = (1_700_000_001.0, "A")
    assert station_clock.stamp(5, mono.t - 1.5, halt) == Stamp.of(1_700_000_001.0, 5, "A")
    other = (1_700_000_001.0, "B")  # (another process's halt says nothing of this one's time)
    assert station_clock.stamp(5, mono.t - 1.5, other) == Stamp.of(1_700_000_000.5, 5, "A")
    assert station_clock.stamp(5, seen_s=mono.t + 1.0) == now  # (no later than when sent)
    assert station_clock.stamp(5) == now  # rule 8: not earlier than the last send time
    mono.t += 0.0007  # (0.7 ms on: the stamp stays in its millisecond, never rounded up)
    assert station_clock.stamp(5) == now
