"""MqttService without a broker: statuses in, what would be published out; messages in, the
rotator calls they become.

The publisher is a recorder of the Publisher protocol: it keeps what the broker would hold
retained and the messages that would go out, honouring ``only_if_changed`` as its contract says.
The rotator is a recorder of RotatorPort calls.
"""

from __future__ import annotations

import json
import math
import threading
from dataclasses import replace

import pytest

from bridge.core.errors import Refused
from bridge.core.model import (
    Claim,
    Command,
    ErrorEvent,
    FollowQso,
    GoToPreset,
    Lock,
    MotionState,
    Nudge,
    Origin,
    Park,
    Release,
    ResetHealth,
    RotatorStatus,
    SetOption,
    Source,
    Stop,
    TakePath,
    Target,
    Toward,
    TrackBody,
)
from bridge.interfaces.mqtt.halts import (
    FENCED,
    HELD,
    LOCK_OFF_FENCED,
    LOCK_OFF_OLDER,
    LOCK_OFF_SUBSCRIBING,
    LOCK_OFF_UNORDERED,
)
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from tests.support import wait_until
from tests.support.clock import FakeClock

NOW_UNIX = 1_700_000_000.0
NOW_ISO = "2023-11-14T22:13:20.000+00:00"


class RecordingPublisher:
    def __init__(self) -> None:
        self.retained: dict[str, str] = {}  # what the broker would hold
        self.sent: list[tuple[str, str, bool]] = []  # (topic, payload, retain), in order
        self.log: list[str] = []  # lifecycle calls

    def publish_retained(
        self, topic: str, payload: str | bytes, *, only_if_changed: bool = True
    ) -> None:
        text = payload.decode() if isinstance(payload, bytes) else payload
        if only_if_changed and self.retained.get(topic) == text:
            return
        self.retained[topic] = text
        self.sent.append((topic, text, True))

    def publish_event(self, topic: str, payload: str | bytes, *, lapses: bool = False) -> None:
        text = payload.decode() if isinstance(payload, bytes) else payload
        self.sent.append((topic, text, False))

    def publish_marker(self, topic: str, payload: str) -> None:
        self.sent.append((topic, payload, False))

    up = hears = True

    def publish_offline_now(self, topics: list[str], last: dict[str, str] | None = None) -> None:
        self.log.append("offline " + " ".join(topics))
        self.retained.update(last or {})
        for topic in topics:
            self.retained[topic] = "offline"

    def start(self) -> None:
        self.log.append("start")

    def stop(self) -> None:
        self.log.append("stop")

    def take(self) -> list[tuple[str, str, bool]]:
        sent, self.sent = self.sent, []
        return sent


class RecordingRotator:
    def __init__(self, rotator_id: str, model: str, refuse: Refused | None = None) -> None:
        self.id = rotator_id
        self.name = rotator_id.title()
        self.spec = REGISTRY[model]
        self.pointing = Pointing.of(self.spec, presets={"EU": (45.0, None)})
        self.calls: list[tuple[object, ...]] = []
        self.origins: list[Origin | None] = []  # who sent each command that names one
        self._refuse = refuse
        self.can_track = False
        self.halted_s = -math.inf  # (no halt is timed here: the judge's, runtime/rotator.py)
        self.halted_unix: float | None = None  # (its stamp, when a test sets one)
        self.can_follow = False

    @property
    def status(self) -> RotatorStatus:
        return RotatorStatus(self.id)

    @property
    def halts(self) -> int:
        return 0  # (no halt is counted here: the judge's, runtime/rotator.py)

    @property
    def halted(self) -> tuple[float, float | None]:
        return self.halted_s, self.halted_unix  # (runtime/rotator.py's, as a test sets it)

    def submit(
        self,
        command: Command,
        described: str | None = None,
        *,
        hold: int | None = None,
        echo: bool = False,
        since: int | None = None,
    ) -> None:
        """Every command the service sends, recorded as what it asks for (who sent it: in
        ``origins``)."""
        self.calls.append(self._recorded(command, described, hold))
        self.origins.append(command.origin)
        if self._refuse is not None and isinstance(command, Target | Stop | SetOption):
            raise self._refuse

    @staticmethod
    def _recorded(command: Command, what: str | None, hold: int | None) -> tuple[object, ...]:
        held = [hold] if hold else []
        src = command.source
        match command:
            case Target() | Stop() | SetOption():
                return ("submit", replace(command, origin=None), what, *held)
            case Lock():
                return ("lock", command.on, *held)
            case FollowQso():
                return ("follow", command.on, command.long_path, src, what)
            case GoToPreset():
                return ("preset", command.name, src, what)
            case Park():
                return ("park", src, what)
            case TakePath():
                return ("path", command.long_path, src, what)
            case Nudge():
                return ("nudge", command.d_az_deg, command.d_el_deg, src, what)
            case Claim():
                return ("claim", command.operator, command.minutes, what)
            case Release():
                return ("release_control", what)
            case Toward():
                lat, lon = round(command.latitude_deg, 4), round(command.longitude_deg, 4)
                return ("toward", lat, lon, command.locator, command.long_path, src, what)
            case TrackBody():
                return ("track", command.name, command.tle, src, what)
            case ResetHealth():
                return ("reset_health",)
        raise AssertionError(command)

    def report_refusal(
        self, message: str, command: str | None, *, origin: Origin | None = None
    ) -> None:
        self.calls.append(("refused", message, command))

    def audit_refusal(self, message: str, command: str, origin: Origin) -> None:
        self.calls.append(("audited", message, command, origin.who))

    def release(self, marker: int, *, clear: bool = False) -> None:
        self.calls.append(("release", marker, *(["clear"] if clear else [])))


def service(
    models: dict[str, str], *, station: str | None = None, **rotator_kw: object
) -> tuple[MqttService, RecordingPublisher, dict[str, RecordingRotator]]:
    """``station``: the process the station's heartbeats name (heartbeat.py rule 7)."""
    roots = {rid: "rotor" if len(models) == 1 else f"rotor/{rid}" for rid in models}
    pub = RecordingPublisher()
    svc = MqttService(Topics("rotor", roots), pub, wall=lambda: NOW_UNIX, station=station)
    rots = {rid: RecordingRotator(rid, m, **rotator_kw) for rid, m in models.items()}  # type: ignore[arg-type]
    for rot in rots.values():
        svc.attach(rot)
    pub.take()  # each rotator's presets (test_attaching_publishes_the_presets...)
    pub.retained.clear()
    return svc, pub, rots


def test_attaching_publishes_the_presets_and_what_the_rotator_is_retained() -> None:
    pub = RecordingPublisher()
    svc = MqttService(Topics("rotor", {"tower": "rotor"}), pub, wall=lambda: NOW_UNIX)
    svc.attach(RecordingRotator("tower", "rotorez"))
    (presets, info) = pub.take()
    assert presets == ("rotor/presets", '{"EU":45}', True)
    assert info[0] == "rotor/info" and info[2] is True
    assert json.loads(info[1]) == {
        "id": "tower",
        "name": "Tower",
        "model": "rotorez",
        "model_name": REGISTRY["rotorez"].display_name,
        "has_elevation": False,
        "can_report_position": True,
        "can_track": False,
        "azimuth_range": [0.0, 360.0],
        "elevation_range": None,
        "keep_out": [],
        "park": None,
        "options": sorted(REGISTRY["rotorez"].options),
        "settings": [
            {"name": name, "label": label, "kind": "bool"}
            for name, label in [
                ("endpoint", "Endpoint option"),
                ("jam", "Jam protection"),
                ("overshoot", "Overshoot option"),
                ("unstick", "Unstick option"),
            ]
        ],
    }


# -- outbound ------------------------------------------------------------------------------------
def test_an_az_only_status_becomes_its_retained_topics() -> None:
    svc, pub, _ = service({"tower": "rotorez"})
    svc.publish_status(
        "tower",
        RotatorStatus(
            "tower",
            state=MotionState.MOVING,
            bearing_deg=123.0,
            target_az_deg=200.0,
            connected=True,
            available=True,
            version="1.4S",
            options={"jam": True, "endpoint": False, "bogus": True},
            last_command_source="mqtt",
        ),
    )
    status = (
        '{"bearing":123.0,"target":200.0,"parked":false,"state":"moving","moving":true,"connected":true,'
        '"available":true,"locked":false,"version":"1.4S","options":{"bogus":true,'
        '"endpoint":false,"jam":true},"last_error":null,"last_command_source":"mqtt",'
        '"last_operator":null,"control":null,'
        f'"estimated":false,"time":"{NOW_ISO}"}}'
    )
    assert pub.take() == [
        ("rotor/bearing", "123", True),
        ("rotor/state", "moving", True),
        ("rotor/availability", "online", True),
        ("rotor/version", "1.4S", True),
        ("rotor/option/endpoint/state", "OFF", True),
        ("rotor/option/jam/state", "ON", True),
        ("rotor/lock/state", "OFF", True),
        ("rotor/status", status, True),
        ("rotor/control", '{"holder":null,"until":null}', True),
    ]


def test_an_az_el_status_adds_elevation_topic_and_fields() -> None:
    svc, pub, _ = service({"sat": "rot2prog"})
    svc.publish_status(
        "sat",
        RotatorStatus(
            "sat",
            state=MotionState.IDLE,
            bearing_deg=-10.5,
            elevation_deg=45.25,
            target_el_deg=45.0,
            connected=True,
            available=True,
            locked=True,
        ),
    )
    assert pub.retained["rotor/bearing"] == "-10.5"
    assert pub.retained["rotor/elevation"] == "45.25"
    assert pub.retained["rotor/lock/state"] == "ON"
    # no version known: cleared (another controller's may be there, runtime/kept.py rule 11)
    assert pub.retained["rotor/version"] == ""
    doc = json.loads(pub.retained["rotor/status"])
    assert (doc["elevation"], doc["target_elevation"], doc["locked"]) == (45.25, 45.0, True)


def test_a_controller_without_position_publishes_no_bearing() -> None:
    svc, pub, _ = service({"tower": "dcu1"})
    svc.publish_status(
        "tower", RotatorStatus("tower", state=MotionState.UNKNOWN, connected=True, available=True)
    )
    assert sorted(pub.retained) == [
        "rotor/availability",
        "rotor/control",
        "rotor/lock/state",
        "rotor/state",
        "rotor/status",
        "rotor/version",  # cleared: it has none (runtime/kept.py rule 11)
    ]
    assert pub.retained["rotor/state"] == "unknown"
    doc = json.loads(pub.retained["rotor/status"])
    assert doc["bearing"] is None and "elevation" not in doc


def test_offline_rotator_status() -> None:
    svc, pub, _ = service({"tower": "rotorez"})
    svc.publish_status("tower", RotatorStatus("tower"))
    assert (pub.retained["rotor/state"], pub.retained["rotor/availability"]) == (
        "offline",
        "offline",
    )
    assert "rotor/bearing" not in pub.retained


def test_only_what_changed_is_published_again() -> None:
    svc, pub, _ = service({"tower": "rotorez"})
    still = RotatorStatus(
        "tower", state=MotionState.IDLE, bearing_deg=90.0, available=True, connected=True
    )
    svc.publish_status("tower", still)
    assert len(pub.take()) == 7  # bearing, state, availability, version, lock, status, control
    svc.publish_status("tower", still)
    assert pub.take() == []
    svc.publish_status(
        "tower",
        RotatorStatus(
            "tower", state=MotionState.IDLE, bearing_deg=91.0, available=True, connected=True
        ),
    )
    assert [topic for topic, _, _ in pub.take()] == ["rotor/bearing", "rotor/status"]


def test_a_reading_hands_the_client_only_what_changed_and_stop_forgets_what_was_handed() -> None:
    """Each hand-off takes the client's lock and encodes the payload (a reading's cost): a
    reading that moves the bearing hands on the bearing and the status, nothing else. After
    ``stop`` (offline published), a status hands everything on again."""
    svc, pub, _ = service({"tower": "rotorez"})
    calls: list[str] = []
    record = pub.publish_retained

    def counting(topic: str, payload: str | bytes, *, only_if_changed: bool = True) -> None:
        calls.append(topic)
        record(topic, payload, only_if_changed=only_if_changed)

    pub.publish_retained = counting  # type: ignore[method-assign]
    for bearing in (90.0, 91.0):
        svc.publish_status(
            "tower",
            RotatorStatus(
                "tower",
                state=MotionState.MOVING,
                bearing_deg=bearing,
                available=True,
                connected=True,
            ),
        )
    assert calls[7:] == ["rotor/bearing", "rotor/status"]
    svc.stop()
    calls.clear()
    svc.publish_status(
        "tower",
        RotatorStatus(
            "tower", state=MotionState.MOVING, bearing_deg=91.0, available=True, connected=True
        ),
    )
    assert "rotor/availability" in calls and pub.retained["rotor/availability"] == "online"


def test_several_rotators_publish_under_their_own_topics_and_listeners_see_statuses() -> None:
    svc, pub, _ = service({"a": "rotorez", "b": "rotorcard"})
    seen: list[tuple[str, MotionState]] = []
    svc.add_feature([], lambda *_: False, lambda rid, st: seen.append((rid, st.state)))
    svc.publish_status("b", RotatorStatus("b", state=MotionState.IDLE, bearing_deg=5.0))
    svc.publish_status("nobody", RotatorStatus("nobody", bearing_deg=1.0))  # before attach
    assert pub.retained["rotor/b/bearing"] == "5"
    assert not any(t.startswith(("rotor/a/", "rotor/nobody")) for t in pub.retained)
    assert seen == [("b", MotionState.IDLE)]


def test_error_events_go_to_the_error_topic_not_retained() -> None:
    svc, pub, _ = service({"a": "rotorez", "b": "rotorez"})
    svc.publish_event("b", ErrorEvent("stalled", "no progress for 10 s", None, NOW_UNIX))
    svc.publish_event("b", ErrorEvent("refused", "azimuth 400 outside 0..360", "target '400'", 1))
    stalled = '{"kind":"stalled","message":"no progress for 10 s","time":1700000000.0}'
    refused = (
        '{"kind":"refused","message":"azimuth 400 outside 0..360","command":"target \'400\'",'
        '"time":1}'
    )
    assert pub.take() == [("rotor/b/error", stalled, False), ("rotor/b/error", refused, False)]
    assert pub.retained == {}


def test_stop_marks_every_rotator_offline_before_the_connection_closes() -> None:
    svc, pub, _ = service({"a": "rotorez", "b": "dcu1"})
    svc.start()
    svc.stop()
    assert pub.log == ["start", "offline rotor/a/availability rotor/b/availability", "stop"]


# -- inbound -------------------------------------------------------------------------------------
M = Source.MQTT


@pytest.mark.parametrize(
    ("topic", "payload", "call"),
    [
        ("rotor/b/target", b"120", ("submit", Target(120.0, None, M), "target '120'")),
        ("rotor/b/target", b" 120.5 ", ("submit", Target(120.5, None, M), "target ' 120.5 '")),
        ("rotor/b/target", b"120 30", ("submit", Target(120.0, 30.0, M), "target '120 30'")),
        (
            "rotor/b/target",
            b'{"azimuth": 10, "elevation": 5}',
            ("submit", Target(10.0, 5.0, M), 'target \'{"azimuth": 10, "elevation": 5}\''),
        ),
        (
            "rotor/b/target/elevation",
            b"30",
            ("submit", Target(None, 30.0, M), "target_elevation '30'"),
        ),
        ("rotor/b/stop", b"STOP", ("submit", Stop(M), "stop 'STOP'")),
        ("rotor/b/stop", b"", ("submit", Stop(M), "stop")),  # a plain stop takes any payload
        ("rotor/b/lock", b"ON", ("lock", True)),
        ("rotor/b/lock", b"false", ("lock", False)),
        # (a name the model does not declare goes to its judge as text, refused there)
        ("rotor/b/option/jam", b"on", ("submit", SetOption("jam", "on", M), "option jam 'on'")),
        (
            "rotor/b/option/unstick",
            b"0",
            ("submit", SetOption("unstick", "0", M), "option unstick '0'"),
        ),
        ("rotor/b/preset", b" EU ", ("preset", "EU", M, "preset ' EU '")),
        ("rotor/b/park", b"PRESS", ("park", M, "park 'PRESS'")),  # any payload but empty
        # a Node-RED inject node's timestamp, and a JSON string that says park
        ("rotor/b/park", b"1764806400000", ("park", M, "park '1764806400000'")),
        ("rotor/b/park", b'"PARK"', ("park", M, "park '\"PARK\"'")),
        ("rotor/b/nudge", b"+10", ("nudge", 10.0, None, M, "nudge '+10'")),
        ("rotor/b/nudge", b"-2.5", ("nudge", -2.5, None, M, "nudge '-2.5'")),
        (
            "rotor/b/nudge",
            b'{"elevation": -2}',
            ("nudge", 0.0, -2.0, M, "nudge '{\"elevation\": -2}'"),
        ),
        ("rotor/b/track", b" sun ", ("track", "sun", None, M, "track ' sun '")),
        ("rotor/b/follow", b"wsjtx", ("follow", True, False, M, "follow 'wsjtx'")),
        ("rotor/b/follow", b" WSJTX ", ("follow", True, False, M, "follow ' WSJTX '")),
        ("rotor/b/follow", b"off", ("follow", False, False, M, "follow 'off'")),
        ("rotor/b/follow", b'{"source": "wsjtx", "path": "long"}',
         ("follow", True, True, M, "follow '{\"source\": \"wsjtx\", \"path\": \"long\"}'")),
        ("rotor/b/track", b"ISS (ZARYA)", ("track", "ISS (ZARYA)", None, M,
                                           "track 'ISS (ZARYA)'")),
        ("rotor/b/track", b'{"tle": ["X", "1 a", "2 b"]}',
         ("track", "X", ("X", "1 a", "2 b"), M, "track '{\"tle\": [\"X\", \"1 a\", \"2 b\"]}'")),
        ("rotor/b/track", b'{"tle": ["1 25544U", "2 25544"]}',
         ("track", "25544", ("25544", "1 25544U", "2 25544"), M,
          "track '{\"tle\": [\"1 25544U\", \"2 25544\"]}'")),
        # JO62qm's centre: 52.5208 N 13.375 E; PM95vq: 35.6875 N 139.7917 E
        ("rotor/b/target", b"PM95vq", ("toward", 35.6875, 139.7917, "PM95vq", False, M,
                                       "target 'PM95vq'")),
        ("rotor/b/target", b"pm95VQ", ("toward", 35.6875, 139.7917, "PM95vq", False, M,
                                       "target 'pm95VQ'")),
        ("rotor/b/target", b'{"locator": "PM95vq", "path": "long"}',
         ("toward", 35.6875, 139.7917, "PM95vq", True, M,
          "target '{\"locator\": \"PM95vq\", \"path\": \"long\"}'")),
        ("rotor/b/target", b'{"path": "long"}', ("path", True, M, "target '{\"path\": \"long\"}'")),
        # a field alone only in JSON (Home Assistant's locator box sends it so)
        ("rotor/b/target", b'{"locator": "JA"}', ("toward", -85.0, 10.0, "JA", False, M,
                                                 "target '{\"locator\": \"JA\"}'")),
        ("rotor/b/target", b'{"latitude": 35.7, "longitude": 139.7}',
         ("toward", 35.7, 139.7, None, False, M,
          "target '{\"latitude\": 35.7, \"longitude\": 139.7}'")),
    ],
)  # fmt: skip
def test_each_command_topic_reaches_its_rotator(
    topic: str, payload: bytes, call: tuple[object, ...]
) -> None:
    svc, pub, rots = service({"a": "rot2prog", "b": "rot2prog"})  # the rotator judges the rest
    svc.on_message(topic, payload, False)
    assert rots["b"].calls == [call]
    assert rots["a"].calls == []
    assert [m for m in pub.sent if "/bridge/fence" not in m[0]] == []  # (markers: lastword)


@pytest.mark.parametrize(
    ("topic", "payload", "message", "what"),
    [
        ("rotor/target", b"north", "azimuth must be a number, got 'north'", "target 'north'"),
        ("rotor/target", b"", "empty payload", "target"),
        ("rotor/target", b"1 2 3", "target must be 'azimuth' or 'azimuth elevation', got '1 2 3'",
         "target '1 2 3'"),
        ("rotor/target", b'{"az": 1, "x": 2}', "unknown key(s) in target: x",
         "target '{\"az\": 1, \"x\": 2}'"),
        ("rotor/target", b"nan", "azimuth must be a number, got 'nan'", "target 'nan'"),
        ("rotor/target", b"\xff", "payload is not UTF-8 text", "target '\ufffd'"),
        ("rotor/target/elevation", b"up", "elevation must be a number, got 'up'",
         "target_elevation 'up'"),
        ("rotor/lock", b"maybe", "expected ON or OFF, got 'maybe'", "lock 'maybe'"),
        # as sent: an attack pass saw '{"call":"ja1abc"}' for {"call":"JA1ABC"}
        ("rotor/lock", b"Locked", "expected ON or OFF, got 'Locked'", "lock 'Locked'"),
        ("rotor/option/jam", b"2", "expected ON or OFF, got '2'", "option jam '2'"),
        ("rotor/target", b"JZ62", "locator 'JZ62': second character must be a letter A..R, got 'Z'",
         "target 'JZ62'"),
        # a bare field is more often a preset's name sent to the wrong topic (cold review)
        ("rotor/target", b"JA", "'JA' is no bearing; a bare locator has 4, 6 or 8 characters (a "
         'field alone: {"locator": "JA"}; a preset goes to the preset topic)', "target 'JA'"),
        ("rotor/target", b'{"locator": "PM95", "path": "longest"}',
         '"path" must be "short" or "long", got "longest"',
         "target '{\"locator\": \"PM95\", \"path\": \"longest\"}'"),
        ("rotor/target", b'{"latitude": 95, "longitude": 0}',
         "latitude must be -90..90 and longitude -180..180",
         "target '{\"latitude\": 95, \"longitude\": 0}'"),
        ("rotor/target", b'{"locator": "PM95", "latitude": 1}',
         'give "locator" or "latitude"/"longitude", not both',
         "target '{\"locator\": \"PM95\", \"latitude\": 1}'"),
        ("rotor/nudge", b"left", "nudge must be a number, got 'left'", "nudge 'left'"),
        ("rotor/track", b'{"tle": "x"}', 'track: JSON must be {"tle": ["NAME", "1 ...", "2 ..."]}',
         "track '{\"tle\": \"x\"}'"),
        # attack 20: one rule for every topic's words (payloads.py ``_words``), naming it
        ("rotor/track", b"a\x07b", "payload holds U+0007, which no command's words hold (a "
         "control character or a non-character; a C string's NUL is taken only at the end)",
         "track 'a\\x07b'"),
        # a TLE's name as a bare one's (an attack pass: a forged log line, escapes retained)
        ("rotor/track", b'{"tle": ["E\\nF", "1 a", "2 b"]}',
         "track: the TLE's name is at most 255 printable characters, and its lines printable text",
         "track '{\"tle\": [\"E\\\\nF\", \"1 a\", \"2 b\"]}'"),
        ("rotor/preset", b"", "empty payload", "preset"),
        ("rotor/follow", b"on", "follow: expected wsjtx or off, got 'on'", "follow 'on'"),
        ("rotor/follow", b'{"source": "wsjtx", "path": 1}',
         'follow: "path" must be "short" or "long", got 1',
         "follow '{\"source\": \"wsjtx\", \"path\": 1}'"),
        ("rotor/follow", b'{"source": "jtalert"}',
         "follow: expected wsjtx or off, got 'jtalert'", "follow '{\"source\": \"jtalert\"}'"),
        ("rotor/follow", b'{"path": "long"}', "follow: expected wsjtx or off, got null",
         "follow '{\"path\": \"long\"}'"),
        ("rotor/follow", b'{"source": "wsjtx", "band": 20}', "unknown key(s) in follow: band",
         "follow '{\"source\": \"wsjtx\", \"band\": 20}'"),
        # MQTT 5; under 3.1.1 an empty plain message is a deletion (test_under_mqtt_3_1_1_...)
        ("rotor/park", b"", "empty payload", "park"),
        # an attack pass: 4096 bytes of 0xFF parked the rotor, and so did a switch's OFF
        ("rotor/park", b"\xff" * 8, "payload is not UTF-8 text", "park '" + "\ufffd" * 8 + "'"),
        ("rotor/park", b"P" * 4096, "payload too large (4096 bytes, at most 256)",
         "park '" + "P" * 256 + "'\u2026"),
        ("rotor/park", b"OFF", "'OFF' does not park: send PARK", "park 'OFF'"),
        ("rotor/park", b"0", "'0' does not park: send PARK", "park '0'"),
        # an attack pass: each of these parked the rotor
        ("rotor/park", b"no", "'no' does not park: send PARK", "park 'no'"),
        ("rotor/park", b"null", "'null' does not park: send PARK", "park 'null'"),
        ("rotor/park", b"0.0", "'0.0' does not park: send PARK", "park '0.0'"),
        ("rotor/park", b'"off"', "'\"off\"' does not park: send PARK", "park '\"off\"'"),
        ("rotor/park", b'{"park": false}', "'{\"park\": false}' does not park: send PARK",
         "park '{\"park\": false}'"),
        ("rotor/health/reset", b"false",
         "'false' does not reset rotor health: send RESET", "health_reset 'false'"),
    ],
)  # fmt: skip
def test_a_bad_payload_is_refused_and_nothing_moves(
    topic: str, payload: bytes, message: str, what: str
) -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    svc.on_message(topic, payload, False)
    assert rots["tower"].calls == [("refused", message, what)]


def test_a_command_the_rotator_refuses_is_left_to_it_to_report() -> None:
    svc, pub, rots = service({"tower": "rotorez"}, refuse=Refused("limits", "outside 0..360"))
    svc.on_message("rotor/target", b"400", False)  # the rotator judges limits, not the service
    assert rots["tower"].calls == [("submit", Target(400.0, None, M), "target '400'")]
    assert pub.sent == []


@pytest.mark.parametrize(
    ("topic", "what"),
    [
        ("rotor/target", "target '120'"),
        ("rotor/target/elevation", "target_elevation '120'"),
        ("rotor/lock", "lock '120'"),
        ("rotor/option/jam", "option jam '120'"),
        ("rotor/preset", "preset '120'"),
        ("rotor/park", "park '120'"),  # a retained PARK is the likeliest mistake of all
        ("rotor/nudge", "nudge '120'"),
    ],
)
def test_a_retained_command_is_refused_not_executed(topic: str, what: str) -> None:
    svc, _, rots = service({"tower": "rotorez"})
    svc.on_message(topic, b"120", True)
    assert rots["tower"].calls == [
        (
            "refused",
            f"retained command on {topic} ignored: commands must be published without the "
            "retain flag (clear it with an empty retained message)",
            what,
        )
    ]


def test_a_retained_stop_is_executed_and_reported() -> None:
    svc, _, rots = service({"tower": "rotorez"})
    svc.on_message("rotor/stop", b"STOP", True)
    assert rots["tower"].calls == [
        ("submit", Stop(M), "stop 'STOP'"),
        (
            "refused",
            "stop on rotor/stop was published retained: executed (stopping is always safe), "
            "but clear it with an empty retained message",
            "stop 'STOP'",
        ),
    ]


def test_other_topics_go_to_the_features_and_subscriptions_include_theirs() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    got: list[tuple[str, str, bytes, bool]] = []

    def feature(name: str, mine: str):  # noqa: ANN202
        def handle(topic: str, payload: bytes, retain: bool) -> bool:
            got.append((name, topic, payload, retain))
            return topic == mine

        return handle

    svc.add_feature(["ha/status"], feature("first", "ha/status"))
    svc.add_feature(["x/#"], feature("second", "x/y"))
    assert svc.subscriptions() == [
        "rotor/target",
        "rotor/target/elevation",
        "rotor/stop",
        "rotor/lock",
        "rotor/option/+",
        "rotor/preset",
        "rotor/park",
        "rotor/nudge",
        "rotor/track",
        "rotor/follow",
        "rotor/health/reset",
        "rotor/control/claim",
        "rotor/control/release",
        "rotor/bridge/fence",
        "ha/status",
        "x/#",
    ]
    svc.on_message("ha/status", b"online", False)
    svc.on_message("x/y", b"1", True)
    svc.on_message("rotor/bearing", b"5", True)  # our own state echoed: nobody's command
    svc.on_message("rotor/target", b"5", False)
    assert got == [
        ("first", "ha/status", b"online", False),
        ("first", "x/y", b"1", True),
        ("second", "x/y", b"1", True),
        ("first", "rotor/bearing", b"5", True),
        ("second", "rotor/bearing", b"5", True),
    ]
    assert rots["tower"].calls == [("submit", Target(5.0, None, M), "target '5'")]


def test_a_lane_stop_holds_the_rotator_until_the_main_connection_reads_its_own_copy() -> None:
    """Rule 5 (lastword.py rules 1, 2 and 9): the lane's stop is carried out at once with a
    hold; a move the main connection reads before its own copy of the stop was published
    before it: refused (review 18: held, it went out when the marker ended the hold with that
    copy lost); what comes after the copy is taken, and waits under the hold (lastword.py
    rule 13: review 22, the count may be wrong) until the marker ends it."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.on_lane_message("rotor/stop", b"", False)
    (marker,) = [m for m in pub.take() if m[0] == "rotor/bridge/fence"]
    svc.on_message("rotor/target", b"300", False)  # published before the stop
    svc.on_message("rotor/stop", b"", False)  # the main connection's copy
    svc.on_message("rotor/target", b"250", False)  # published after it
    svc.on_lane_message("rotor/lock", b"OFF", False)  # never from the lane: in order on main
    svc.on_message("rotor/bridge/fence", b"not-ours 1", False)  # another's marker: nothing
    svc.on_message(marker[0], marker[1].encode(), False)
    stop = Stop(Source.MQTT)
    assert tower.calls == [
        ("submit", stop, "stop", 1),
        ("refused", HELD, "target '300'"),
        ("submit", stop, "stop"),
        ("submit", Target(250.0, None, M), "target '250'"),
        ("release", 1),
    ]


def test_the_lanes_late_copy_of_a_stop_the_main_connection_carried_out_is_its_echo() -> None:
    """lastword.py rule 4: main read it first; the lane's copy must not stop the target
    published after the stop (already on its way). The lane marker, once back, ends the
    note: the next lane stop is carried out at once."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.on_message("rotor/stop", b"", False)
    (lane_marker,) = [m for m in pub.take() if m[0] == "rotor/bridge/fence/lane"]
    svc.on_message("rotor/target", b"250", False)
    svc.on_lane_message("rotor/stop", b"", False)  # the echo
    svc.on_message("rotor/stop", b"", False)  # one the lane missed (it was down) ...
    (lane_marker,) = [m for m in pub.take() if m[0] == "rotor/bridge/fence/lane"]
    svc.on_lane_message(lane_marker[0], lane_marker[1].encode(), False)
    svc.on_lane_message("rotor/stop", b"", False)  # ... so this one is new
    stop = Stop(Source.MQTT)
    assert tower.calls == [
        ("submit", stop, "stop"),
        ("submit", Target(250.0, None, M), "target '250'"),
        ("submit", stop, "stop"),
        ("submit", stop, "stop", 1),
    ]


def test_a_lock_off_read_while_the_lanes_on_waits_for_its_copy_is_older() -> None:
    """lastword.py rule 8: the ON stands even if the main connection drops before its copy."""
    svc, _pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.on_lane_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"OFF", False)  # published before the ON
    svc.main_gone()
    assert [c for c in tower.calls if c[0] == "lock"] == [("lock", True, 1)]
    # said on R/error, not only logged (an attack pass: right after the lane reconnected, an
    # OFF published after the ON was refused so too, with only an INFO line for it)
    assert ("refused", LOCK_OFF_OLDER, "lock OFF") in tower.calls


def test_moves_and_a_lock_off_read_behind_another_interfaces_halt_are_refused_as_older() -> None:
    """lastword.py rule 11 (an attack pass): the console's lock ON, then a lock OFF and a
    target published before it, read late on the main connection, unlocked and turned the
    rotor. Fenced until the halt's marker comes back: refused, said on R/error; a stop fences
    the moves alone; after the marker both are taken again."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.fence_asked("tower")
    svc.fence_carried("tower", lock=True)  # the console's lock ON, put between the two
    ((topic, marker, _),) = [m for m in pub.take() if m[0] == "rotor/bridge/fence"]
    svc.on_message("rotor/lock", b"OFF", False)
    svc.on_message("rotor/target", b"120", False)
    svc.on_message("rotor/preset", b"EU", False)
    svc.on_message("rotor/nudge", b"10", False)
    assert tower.calls == [
        ("refused", LOCK_OFF_FENCED, "lock OFF"),
        ("refused", FENCED, "target '120'"),
        ("refused", FENCED, "preset 'EU'"),
        ("refused", FENCED, "nudge '10'"),
    ]
    tower.calls.clear()
    svc.on_message("rotor/option/jam", b"OFF", False)  # moves nothing: taken
    svc.on_message(topic, marker.encode(), False)  # the main connection caught up
    svc.on_message("rotor/lock", b"OFF", False)
    svc.on_message("rotor/target", b"120", False)
    assert [c[0] for c in tower.calls] == ["submit", "lock", "submit"]
    tower.calls.clear()
    svc.fence_asked("tower")
    svc.fence_carried("tower", lock=False)  # rotctld's S
    svc.on_message("rotor/lock", b"OFF", False)  # a stop fences no lock word
    svc.on_message("rotor/target", b"120", False)
    assert tower.calls == [("lock", False), ("refused", FENCED, "target '120'")]


def test_a_target_behind_the_copy_of_a_lane_stop_read_late_stays_fenced() -> None:
    """lastword.py rule 11 (a review): an MQTT STOP, a target of 120, then rotctld's S; the
    lane reads the MQTT STOP after the S was fenced. The main connection's copy of that stop
    ended the fence, and the target, published before the S, turned the rotor after it."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.fence_asked("tower")
    svc.fence_carried("tower", lock=False)  # rotctld's S
    svc.on_lane_message("rotor/stop", b"", False)  # the MQTT STOP published before it
    svc.on_message("rotor/stop", b"", False)  # its copy on the main connection
    tower.calls.clear()
    svc.on_message("rotor/target", b"120", False)
    assert tower.calls == [("refused", FENCED, "target '120'")]


def test_a_fence_ends_by_its_markers_copy_on_the_hello_topic_when_the_fence_topic_drops_it() -> (
    None
):
    """lastword.py rule 7 (an attack pass): the broker began dropping B/bridge/fence under a
    live connection (mosquitto reloads its ACL on SIGHUP), and after rotctld's S every MQTT
    target was refused as older until the connection dropped. Each marker goes on the hello
    topic too, and that copy ends the fence; a hello that is no marker of this process ends
    nothing."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.fence_asked("tower")
    svc.fence_carried("tower", lock=False)  # rotctld's S
    sent = pub.take()
    (fence,) = [p for t, p, _ in sent if t == "rotor/bridge/fence"]
    assert [p for t, p, _ in sent if t == "rotor/bridge/hello"] == [fence]
    svc.on_message("rotor/target", b"120", False)  # published before the S
    token, number, _seal = fence.split()
    svc.on_message("rotor/bridge/hello", f"{token} {number} {'0' * 16}".encode(), False)
    svc.on_message("rotor/bridge/hello", b"another-bridge 1", False)  # a hello, no marker
    svc.on_message("rotor/target", b"130", False)  # still before the S's marker
    svc.on_message("rotor/bridge/hello", fence.encode(), False)  # its copy: caught up
    svc.on_message("rotor/target", b"140", False)
    assert [c[:2] for c in tower.calls] == [
        ("refused", FENCED),
        ("refused", FENCED),
        ("submit", tower.calls[-1][1]),
    ]


def test_a_move_read_while_another_interfaces_halt_is_asked_and_not_fenced_yet_is_refused() -> None:
    """lastword.py rule 11: the halt is counted before it is put and fenced after: a move the
    main connection reads in between would otherwise go out after it."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.fence_asked("tower")
    svc.on_message("rotor/target", b"120", False)
    assert tower.calls == [("refused", FENCED, "target '120'")]


def test_a_lock_off_then_on_ends_on_and_on_then_off_ends_off() -> None:
    """lastword.py rule 1: the main connection's words in order are the last word; the lane
    only adds a lock ON at once."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.on_lane_message("rotor/lock", b"OFF", False)
    svc.on_lane_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"OFF", False)  # older than the lane's ON: not carried out
    svc.on_message("rotor/lock", b"ON", False)
    assert [c for c in tower.calls if c[0] == "lock"] == [("lock", True, 1), ("lock", True)]
    tower.calls.clear()
    svc.on_lane_message("rotor/lock", b"ON", False)
    svc.on_lane_message("rotor/lock", b"OFF", False)
    svc.on_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"OFF", False)  # waits for the marker (lastword.py rule 13)
    assert [c for c in tower.calls if c[0] == "lock"] == [("lock", True, 3), ("lock", True)]
    for topic, payload, _r in pub.take():
        if topic == "rotor/bridge/fence":
            svc.on_message(topic, payload.encode(), False)
    assert [c for c in tower.calls if c[0] == "lock"] == [
        ("lock", True, 3),
        ("lock", True),
        ("lock", False),
    ]


def test_a_new_main_connection_ends_the_holds_with_clearing() -> None:
    """lastword.py rule 5: the marker cannot come back on a connection that dropped."""
    svc, pub, rots = service({"tower": "rotorez"})
    svc.on_lane_message("rotor/stop", b"", False)
    svc.main_gone()  # dropped
    svc.main_gone()  # and back: nothing held any more
    assert rots["tower"].calls[1:] == [("release", 0, "clear")]


def test_a_replayed_retained_stop_is_carried_out_once() -> None:
    """lastword.py rule 6, MQTT 3.1.1: a retained stop comes again on every subscription of
    either connection; a new one (another payload, or after deletion) is carried out."""
    pub = RecordingPublisher()
    svc = MqttService(Topics("rotor", {"tower": "rotor"}), pub, retain_is_live=False)
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    svc.on_lane_message("rotor/stop", b"STOP", True)
    svc.on_message("rotor/stop", b"STOP", True)
    svc.on_lane_message("rotor/stop", b"STOP", True)  # the lane reconnected
    svc.on_message("rotor/stop", b"", True)  # deleted
    svc.on_message("rotor/stop", b"STOP", True)
    assert [c[0] for c in tower.calls] == ["submit", "refused", "submit", "refused"]
    live = MqttService(Topics("rotor", {"tower": "rotor"}), pub)  # MQTT 5: every one is live
    tower = RecordingRotator("tower", "rotorez")
    live.attach(tower)
    live.on_message("rotor/stop", b"STOP", True)
    live.on_message("rotor/stop", b"STOP", True)
    assert [c[0] for c in tower.calls] == ["submit", "refused", "submit", "refused"]


def test_under_mqtt_3_1_1_an_empty_message_is_a_deletion_but_an_empty_stop_stops() -> None:
    """Rule 1: under MQTT 3.1.1 the broker clears the retain flag of the empty retained message
    that deletes a retained command while the bridge listens (docs/mqtt.md: ignored silently)."""
    svc = MqttService(Topics("rotor", {"tower": "rotor"}), RecordingPublisher())
    svc.retain_is_live(False)  # the main connection speaks MQTT 3.1.1
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    for leaf in ("target", "park", "preset", "lock", "option/jam", "health/reset"):
        svc.on_message(f"rotor/{leaf}", b"", False)
    assert tower.calls == []
    svc.on_message("rotor/stop", b"", False)  # a stop takes any payload: never refused
    assert [c[0] for c in tower.calls] == ["submit"]


def test_while_gated_only_halts_are_taken_and_the_rest_is_reported() -> None:
    """Rule 6: the first look runs (or the bridge refused to run)."""
    svc, _pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.on_message("rotor/target", b"300", False, gated=True)
    svc.on_message("rotor/lock", b"ON", False, gated=True)
    svc.on_message("rotor/stop", b"", False, gated=True)
    assert [c[0] for c in tower.calls] == ["refused", "lock", "submit"]
    assert "first look" in str(tower.calls[0][1])


def saying_service() -> tuple[FakeClock, list[tuple[str, bool]], RecordingPublisher, MqttService]:
    """One rotator's service on a fake clock, what it says on B/bridge/info kept."""
    clock = FakeClock(0.0)
    said: list[tuple[str, bool]] = []
    pub = RecordingPublisher()
    svc = MqttService(
        Topics("rotor", {"tower": "rotor"}),
        pub,
        wall=lambda: NOW_UNIX,
        clock=clock,
        on_info=lambda problem, on: said.append((problem, on)),
    )
    return clock, said, pub, svc


def test_a_lane_stop_holds_for_hours_said_while_it_lasts_until_the_main_copy() -> None:
    """lastword.py rule 5, halts.py's timer work in virtual time: markers sent again, never
    given up; the hold said once on B/bridge/info, never ended by the clock; the main
    connection's copy of the stop ends it, and the saying."""
    clock, said, pub, svc = saying_service()
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    svc.on_lane_message("rotor/stop", b"", False)
    for _ in range(3 * 3600):  # three hours of a main connection that reads nothing
        clock.t += 1.0
        svc._halts.resend_if_due()
        svc._halts.say_long_holds()
    assert not [c for c in tower.calls if c[0] == "release"]
    markers = [m for m in pub.sent if m[0] == "rotor/bridge/fence"]
    assert 3 < len(markers) < 3 * 3600 / 20  # sent again, with a back-off
    assert [on for _p, on in said] == [True] and "tower: a stop" in said[0][0]
    svc.on_message("rotor/target", b"300", False)  # published before the stop: held
    svc.on_message("rotor/stop", b"", False)  # its own copy: a fresh marker at once ...
    (fresh,) = [m for m in pub.sent if m[0] == "rotor/bridge/fence"][-1:]
    svc.on_message(fresh[0], fresh[1].encode(), False)  # ... back: the hold ends
    assert tower.calls[-1][0] == "release"
    svc._halts.say_long_holds()
    assert said[-1] == (said[0][0], False)


def test_a_fence_whose_marker_never_comes_back_is_said_while_it_lasts() -> None:
    """lastword.py rule 11 (a review): rotctld's S fenced the rotator and its marker never came
    back (a broker that drops the bridge's own messages, an ACL changed under a live
    connection): every MQTT move was refused as published before the S, for hours, with
    nothing on B/bridge/info, unlike a lane's hold. Said once while it lasts, unsaid when a
    marker ends it."""
    clock, said, pub, svc = saying_service()
    svc.attach(RecordingRotator("tower", "rotorez"))
    svc.fence_asked("tower")
    svc.fence_carried("tower", lock=False)
    for _ in range(3600):  # an hour of markers that never come back
        clock.t += 1.0
        svc._halts.resend_if_due()
        svc._halts.say_long_holds()
    assert [on for _p, on in said] == [True]
    assert said[0][0].startswith("tower: a STOP or lock ON from another interface")
    (last,) = [m for m in pub.sent if m[0] == "rotor/bridge/fence"][-1:]
    svc.on_message(last[0], last[1].encode(), False)  # the main connection caught up
    svc._halts.say_long_holds()
    assert said[-1] == (said[0][0], False)


def test_a_stopped_service_sends_no_marker_again_and_its_timer_ends() -> None:
    """A marker out when the bridge stopped never comes back (here rotctld's S fenced the
    rotator; so does a stop on the lane just before the end): halts.py's timer went on looking
    every second for the rest of the process's life, sending markers on the stopped client,
    each look a new thread. Stopped, the service sends nothing more and its timer ends."""
    clock, _said, pub, svc = saying_service()
    svc.attach(RecordingRotator("tower", "rotorez"))
    svc.fence_asked("tower")
    svc.fence_carried("tower", lock=False)  # its marker out, the timer armed
    assert [m for m in pub.sent if m[0] == "rotor/bridge/fence"]
    svc.stop()
    after_stop = len(pub.sent)
    clock.t += 3600.0  # a marker to send again long due, had the timer looked

    def looking() -> list[threading.Thread]:
        return [
            t
            for t in threading.enumerate()
            if getattr(t, "function", None) == svc._halts._tick and t.is_alive()
        ]

    wait_until(lambda: not looking(), 5, "the stopped service's timer to end")
    assert [m for m in pub.sent[after_stop:] if m[0] == "rotor/bridge/fence"] == []


def test_a_lane_stop_while_the_main_connection_subscribes_holds_what_it_will_read() -> None:
    """An attack pass: between the main connection's SUBSCRIBE and its SUBACK the lane's stop
    held nothing (the main connection counted as down), so a target published before the
    stop, read by the main connection after it, went out after it; and the lane carried out a
    lock OFF the main connection was to read after targets published under the lock."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.up, pub.hears = False, True  # accepted, SUBSCRIBE sent, no SUBACK yet
    svc.on_lane_message("rotor/stop", b"", False)
    assert tower.calls == [("submit", Stop(Source.MQTT), "stop", 1)]  # held, at marker 1
    assert [m for m in pub.take() if m[0] == "rotor/bridge/fence"]  # which went out
    svc.on_lane_message("rotor/lock", b"OFF", False)  # the main connection's to carry out
    assert tower.calls[1:] == [("refused", LOCK_OFF_SUBSCRIBING, "lock 'OFF'")]  # if it reads it


def test_a_lane_lock_off_after_another_interfaces_unfenced_lock_on_is_refused() -> None:
    """lastword.py rule 12 (an attack pass): with the main connection down the stop lane carries
    out a lock OFF (rule 3), and the console's lock ON had no fence (nothing to send its marker
    on): an automation's lock OFF published just before the ON, read by the lane just after it,
    unlocked the rotator under a page that said ON. So did a lane OFF read after the main
    connection dropped with the ON's fence still up. Refused and said; the ON stands. A new
    main connection ends it: a lane OFF after its next drop is carried out."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.up = pub.hears = False  # the main connection is down
    svc.fence_asked("tower")
    svc.fence_carried("tower", lock=True)  # the console's lock ON
    svc.on_lane_message("rotor/lock", b"OFF", False)  # published before it, read after
    assert tower.calls == [("refused", LOCK_OFF_UNORDERED, "lock 'OFF'")]
    tower.calls.clear()
    svc.main_gone()  # a new main connection (before its messages) ...
    pub.up = pub.hears = True
    svc.fence_asked("tower")
    svc.fence_carried("tower", lock=True)  # ... fences the console's next lock ON
    pub.take()
    svc.main_gone()  # ... and drops before its marker came back
    pub.up = pub.hears = False
    svc.on_lane_message("rotor/lock", b"OFF", False)
    assert tower.calls == [("refused", LOCK_OFF_UNORDERED, "lock 'OFF'")]
    tower.calls.clear()
    svc.main_gone()  # a new main connection, back in step; it drops again
    svc.main_gone()
    svc.on_lane_message("rotor/lock", b"OFF", False)  # the only word now: carried out
    assert tower.calls == [("lock", False)]
    tower.calls.clear()
    svc.fence_asked("tower")  # the console's lock ON under way (asked, not yet carried out)
    svc.on_lane_message("rotor/lock", b"OFF", False)
    assert tower.calls == [("refused", LOCK_OFF_UNORDERED, "lock 'OFF'")]


def test_a_stale_lock_off_on_the_lane_is_refused_while_its_stops_are_never() -> None:
    """Rule 9 on the stop lane too: while the main connection is down the lane carries out a
    lock OFF (lastword.py rule 3), but one a stalled link held up past its expiry is refused and
    reported as the main connection would; a stop or lock ON is never judged by its stamp."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.up = pub.hears = False  # the main connection is down
    stale = Stamp.of(NOW_UNIX - 30, 5)
    svc.on_lane_message("rotor/lock", b"OFF", False, "DL1ABC", stale)
    assert [c[0] for c in tower.calls] == ["refused"]
    assert "older than its 5 s expiry" in str(tower.calls[0][1])
    tower.calls.clear()
    svc.on_lane_message("rotor/lock", b"OFF", False, "DL1ABC", Stamp.of(NOW_UNIX - 1, 5))
    svc.on_lane_message("rotor/stop", b"", False, "DL1ABC", stale)
    svc.on_lane_message("rotor/lock", b"ON", False, "DL1ABC", stale)
    assert [c[0] if c[0] == "submit" else c[:2] for c in tower.calls] == [
        ("lock", False),
        "submit",
        ("lock", True),
    ]


def test_every_mqtt_halt_is_shown_to_the_stop_express_first_and_its_failure_costs_no_stop() -> None:
    """interfaces/mqtt/express.py rule 8: its hold goes in before the halt, from either connection,
    a group's stop too; a hook that raises is logged and the stop still goes in."""
    svc, _pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    shown: list[str] = []

    def hold(rid: str) -> None:
        shown.append(rid)
        tower.calls.append(("express", rid))
        if len(shown) == 3:
            raise RuntimeError("a bug in the hook")

    svc.hold_for_express(hold)
    svc.on_lane_message("rotor/stop", b"", False)
    svc.on_message("rotor/stop", b"", False)
    svc.on_message("rotor/lock", b"ON", False)
    kinds = [c[0] if c[0] != "submit" else "stop" for c in tower.calls]
    assert kinds == ["express", "stop", "express", "stop", "express", "lock"]
