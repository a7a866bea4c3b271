"""Groups (interfaces/mqtt/groups.py): the fan-out decision on its own (offsets, limits, elevation,
what a group refuses), and the service's group topics with recording rotators: a group's target as
each member's, a group's stop as each member's on both connections (the last word: a lane's
group stop holds every member until the main connection's copy, so no target published before
it runs after it), refusals on the group's error topic, the group's status."""

from __future__ import annotations

import json
import time

import pytest

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import MotionState, Origin, RotatorStatus, Source, Stop, Target
from bridge.feature import registered
from bridge.interfaces.mqtt import payloads as pl
from bridge.interfaces.mqtt.groups import Group, Member, fan_out, member_bearing, status_json
from bridge.interfaces.mqtt.halts import FENCED, HELD
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import RotatorTopics, Topics
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from bridge.settings.groups import CORE_WORDS, reserved
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator

M = Source.MQTT
STACK = Group("stack", "Stack", (Member("upper"), Member("lower", 180.0)))
AZ_ONLY = {"upper": False, "lower": False}


def targets(parts: list[object]) -> list[tuple[str, float | None, float | None, str | None]]:
    return [
        (p.member, p.target and p.target.az_deg, p.target and p.target.el_deg, p.refused)  # type: ignore[attr-defined]
        for p in parts
    ]


# -- the decision, pure ------------------------------------------------------------------------
def test_each_member_turns_to_the_groups_bearing_plus_its_offset_within_0_to_360() -> None:
    assert targets(fan_out(STACK, b"120", AZ_ONLY)) == [
        ("upper", 120.0, None, None),
        ("lower", 300.0, None, None),
    ]
    assert targets(fan_out(STACK, b"270", AZ_ONLY)) == [
        ("upper", 270.0, None, None),
        ("lower", 90.0, None, None),
    ]
    assert member_bearing(360.0, 0.0) == 360.0  # as sent: the rotator's range decides
    assert member_bearing(180.0, 180.0) == 0.0


def test_a_members_offset_to_north_is_judged_to_the_end_of_its_travel_nearer_it() -> None:
    """Attack 10: the group's 180 is north for a member with offset 180; on a GS-232, whose 0
    and 360 are the two ends of its travel, it went out as 0 wherever the rotor stood (at 355,
    a turn of 355 degrees back through south). Its part names no end: the member's judge takes
    the nearer. A member without an offset takes the group's bearing as sent, an end named as
    its own target names it."""
    aim = Pointing.of(REGISTRY["gs232b-az"])
    upper, lower = (p.target for p in fan_out(STACK, b"180", AZ_ONLY))
    assert lower is not None and lower.az_deg == 0.0 and lower.az_either_end
    assert [aim.judge(lower, at).az_deg for at in (355.0, 5.0, 180.0)] == [360.0, 0.0, 0.0]
    for named in (0.0, 360.0):
        own = next(p.target for p in fan_out(STACK, f"{named:g}".encode(), AZ_ONLY))
        assert own is not None and not own.az_either_end
        assert aim.judge(own, 355.0).az_deg == aim.judge(Target(named), 355.0).az_deg == named


def test_a_member_outside_its_group_limits_is_refused_and_the_others_still_turn() -> None:
    narrow = Group("stack", "Stack", (Member("upper", 0.0, (20.0, 340.0)), Member("lower", 180.0)))
    assert targets(fan_out(narrow, b"10", AZ_ONLY)) == [
        ("upper", None, None, "10 is outside upper's limits in group stack (20..340)"),
        ("lower", 190.0, None, None),
    ]
    assert targets(fan_out(narrow, b"20", AZ_ONLY))[0] == ("upper", 20.0, None, None)


def test_a_members_refusal_never_quotes_a_bearing_inside_its_limits() -> None:
    """Review 87: ':g' quoted 340.0000004 past 20..340 as '340 is outside ... (20..340)', and
    359.9999999 past 0..90 as 360, north, which is inside 0..90 too (north is 0 and 360)."""
    narrow = Group(
        "stack", "Stack", (Member("upper", 0.0, (20.0, 340.0)), Member("lower", 0.0, (0.0, 90.0)))
    )
    said = [p.refused for p in fan_out(narrow, b"340.0000004", AZ_ONLY)]
    assert said[0] == "340.0000004 is outside upper's limits in group stack (20..340)"
    said = [p.refused for p in fan_out(narrow, b"359.9999999", AZ_ONLY)]
    assert said[1] == "359.9999999 is outside lower's limits in group stack (0..90)"


def test_north_is_inside_limits_that_end_at_0_or_at_360() -> None:
    """An attack pass: 360 (Home Assistant's top) was refused for limits 0..90, 0 for limits
    300..360, and the group's 180 plus an offset of 180 for limits 340..360."""
    north = Group(
        "stack",
        "Stack",
        (
            Member("upper", 0.0, (0.0, 90.0)),
            Member("lower", 0.0, (300.0, 360.0)),
            Member("third", 180.0, (340.0, 360.0)),
        ),
    )
    assert [p.refused for p in fan_out(north, b"360", {})][:2] == [None, None]
    assert [p.refused for p in fan_out(north, b"0", {})][:2] == [None, None]
    assert targets(fan_out(north, b"180", {}))[2] == ("third", 0.0, None, None)
    assert targets(fan_out(north, b"91", {}))[0][3] is not None  # still refused beyond


def test_an_elevation_needs_every_member_to_have_one_else_nothing_moves() -> None:
    both = {"upper": True, "lower": True}
    assert targets(fan_out(STACK, b'{"azimuth": 10, "elevation": 30}', both)) == [
        ("upper", 10.0, 30.0, None),
        ("lower", 190.0, 30.0, None),
    ]
    with pytest.raises(pl.PayloadError, match="lower turns in azimuth only"):
        fan_out(STACK, b'{"azimuth": 10, "elevation": 30}', {"upper": True, "lower": False})
    with pytest.raises(pl.PayloadError, match="upper, lower turn in azimuth only"):
        fan_out(STACK, b'{"azimuth": 10, "elevation": 30}', {})


@pytest.mark.parametrize(
    "payload",
    [b"", b"north", b"361", b"-5", b"NaN", b"JO01", b'{"call": "JA1ABC"}', b'{"path": "long"}'],
)
def test_what_is_no_bearing_is_refused_for_the_whole_group(payload: bytes) -> None:
    with pytest.raises(pl.PayloadError):
        fan_out(STACK, payload, AZ_ONLY)


@pytest.mark.parametrize("payload", [b"+10", b"+10 30", b'{"azimuth": "+10"}'])
def test_a_signed_step_on_the_groups_target_is_refused_as_a_nudge(payload: bytes) -> None:
    """Attack 20: ``+10``, the nudge buttons' word, was the bearing 10 for every member."""
    with pytest.raises(pl.PayloadError, match="is a signed step, a nudge: send it to the nudge"):
        fan_out(STACK, payload, {"upper": True, "lower": True})


def test_the_reserved_words_are_every_first_level_of_a_rotators_topics() -> None:
    """settings/groups.py rule 4 in step with topics.py: a group may not take any of them."""
    t = RotatorTopics("R")
    leaves = {
        getattr(t, name).split("/")[1]
        for name in dir(RotatorTopics)
        if isinstance(getattr(RotatorTopics, name), property)
    }
    leaves |= {t.option("x").split("/")[1]}
    assert leaves | {"bridge"} == CORE_WORDS  # the core's, written once
    # and each registered feature's (bridge/feature.py rule 3), under R/ and B/
    words = {x.suffix.split("/")[0] for f in registered() for x in (*f.commands, *f.states)}
    words |= {suffix.split("/")[0] for f in registered() for suffix in f.base_topics}
    assert reserved() == CORE_WORDS | words and "spots" in words


def test_the_groups_status_is_its_members_with_its_refusals() -> None:
    statuses = {
        "upper": RotatorStatus("upper", MotionState.MOVING, 100.0, available=True),
        "lower": RotatorStatus("lower", MotionState.IDLE, 280.0, available=True),
    }
    doc = json.loads(status_json(STACK, statuses, {"lower": "locked"}))
    assert doc["bearing"] == 100.0 and doc["state"] == "moving" and doc["moving"] is True
    assert doc["members"]["lower"] == {
        "bearing": 280.0,
        "elevation": None,
        "state": "idle",
        "available": True,
        "offset": 180.0,
    }
    assert doc["refused"] == {"lower": "locked"} and doc["available"] is True
    gone = {"upper": None, "lower": RotatorStatus("lower")}
    doc = json.loads(status_json(STACK, gone, {}))
    assert doc["state"] == "offline" and doc["available"] is False and doc["bearing"] is None


def test_the_groups_bearing_is_its_first_available_members() -> None:
    """A review: the first member unplugged, the group turned to 100; its status still showed
    the first member's last reading, 10, while the only member that turned pointed at 100."""
    unplugged = RotatorStatus("upper", MotionState.OFFLINE, 10.0, available=False)
    statuses = {
        "upper": unplugged,
        "lower": RotatorStatus("lower", MotionState.IDLE, 280.0, available=True),
    }
    doc = json.loads(status_json(STACK, statuses, {}))
    assert doc["bearing"] == 100.0 and doc["state"] == "idle" and doc["moving"] is False
    alone = {"upper": unplugged, "lower": None}  # none available: the last one known
    assert json.loads(status_json(STACK, alone, {}))["bearing"] == 10.0


def test_the_groups_bearing_a_hair_short_of_north_is_north_not_360() -> None:
    """A member reading 179.97 less its offset of 180 is 359.97: rounded to a tenth, that is
    north, shown as 0.0 (it was 360.0, a bearing the group's scale of 0 to 360 never shows)."""
    statuses = {
        "upper": None,
        "lower": RotatorStatus("lower", MotionState.IDLE, 179.97, available=True),
    }
    assert json.loads(status_json(STACK, statuses, {}))["bearing"] == 0.0


# -- the service -------------------------------------------------------------------------------
def group_service(
    refuse_lower: Refused | None = None,
) -> tuple[MqttService, RecordingPublisher, RecordingRotator, RecordingRotator]:
    roots = {"upper": "rotor/upper", "lower": "rotor/lower", "other": "rotor/other"}
    pub = RecordingPublisher()
    svc = MqttService(Topics("rotor", roots, {"stack": "rotor/stack"}), pub, wall=lambda: NOW_UNIX)
    upper = RecordingRotator("upper", "rotorez")
    lower = RecordingRotator("lower", "rotorez", refuse=refuse_lower)
    for rot in (upper, lower, RecordingRotator("other", "rotorez")):
        svc.attach(rot)
    svc.attach_group(STACK)
    pub.take()
    return svc, pub, upper, lower


def test_the_group_topics_are_subscribed_its_stop_on_the_lane_too() -> None:
    svc, _pub, _upper, _lower = group_service()
    assert {"rotor/stack/target", "rotor/stack/stop"} <= set(svc.subscriptions())
    assert "rotor/stack/stop" in svc.stop_lane_subscriptions()
    assert "rotor/stack/stop" in svc.no_replay_subscriptions()
    assert "rotor/stack/target" not in svc.stop_lane_subscriptions()
    assert {"rotor/stack/status", "rotor/stack/availability"} <= set(svc.topics.owned())


def test_a_group_target_is_a_target_for_each_member_through_its_own_submit() -> None:
    svc, _pub, upper, lower = group_service()
    svc.on_message("rotor/stack/target", b"120", False, "alice")
    assert upper.calls == [("submit", Target(120.0, None, M), "target '120' (group stack)")]
    lowered = Target(300.0, None, M, az_either_end=True)  # (its offset: it names no end)
    assert lower.calls == [("submit", lowered, "target '120' (group stack)")]
    assert upper.origins == [Origin(Source.MQTT, "alice")]


def test_a_members_refusal_is_on_the_groups_error_and_status_and_the_other_turns() -> None:
    locked = Refused(RefusalCode.LOCKED, "locked: unlock it first")
    svc, pub, upper, lower = group_service(refuse_lower=locked)
    svc.on_message("rotor/stack/target", b"120", False)
    assert upper.calls == [("submit", Target(120.0, None, M), "target '120' (group stack)")]
    assert len(lower.calls) == 1
    sent = pub.take()
    (error,) = [json.loads(p) for t, p, _r in sent if t == "rotor/stack/error"]
    assert error["members"] == {"lower": "locked: unlock it first"}
    assert error["kind"] == "refused" and "the others turn" in error["message"]
    status = json.loads(pub.retained["rotor/stack/status"])
    assert status["refused"] == {"lower": "locked: unlock it first"}


def test_a_group_target_stamped_before_a_members_stop_turns_only_the_others() -> None:
    """service.py rule 9 (heartbeat.py rule 8) per member: a group target a link held up,
    stamped before the lower rotor's STOP, is refused for that member alone (on the group's
    error), the upper still turns; one stamped after it turns both."""
    svc, pub, upper, lower = group_service()
    lower.halted_s = time.monotonic() - 1.0  # its STOP came a second ago
    svc.on_message("rotor/stack/target", b"120", False, stamp=Stamp.of(NOW_UNIX - 2.0, 5))
    assert [c[0] for c in upper.calls] == ["submit"]
    assert [c[0] for c in lower.calls] == ["refused"]
    assert "before the last STOP or lock ON" in str(lower.calls[0][1])
    (error,) = [json.loads(p) for t, p, _r in pub.take() if t == "rotor/stack/error"]
    assert "before the last STOP" in error["members"]["lower"]
    svc.on_message("rotor/stack/target", b"130", False, stamp=Stamp.of(NOW_UNIX - 0.5, 5))
    assert [c[0] for c in lower.calls] == ["refused", "submit"]


def test_when_every_member_refuses_the_groups_error_says_none_turns() -> None:
    locked = Refused(RefusalCode.LOCKED, "locked: unlock it first")
    svc, pub, upper, lower = group_service(refuse_lower=locked)
    upper._refuse = Refused(RefusalCode.KEEP_OUT, "azimuth 120 is in the keep-out sector")
    svc.on_message("rotor/stack/target", b"120", False)
    (error,) = [json.loads(p) for t, p, _r in pub.take() if t == "rotor/stack/error"]
    assert set(error["members"]) == {"upper", "lower"}
    assert error["message"].endswith("; none turns")


@pytest.mark.parametrize(
    ("payload", "retain", "why"),
    [
        (b"120", True, "retained command on rotor/stack/target ignored"),
        (b"north", False, "north"),
        (b'{"azimuth": 1, "elevation": 2}', False, "turn in azimuth only"),
        (b"360.0001", False, "0..360, not 360.0001"),  # (not "not 360": as sent)
    ],
)
def test_a_retained_or_bad_group_target_moves_nothing_and_says_why(
    payload: bytes, retain: bool, why: str
) -> None:
    svc, pub, upper, lower = group_service()
    svc.on_message("rotor/stack/target", payload, retain)
    (error,) = [json.loads(p) for t, p, _r in pub.take() if t == "rotor/stack/error"]
    assert why in error["message"] and error["kind"] == "refused"
    # nothing for either member but its audit trail (an attack pass: in none before)
    for member in (upper, lower):
        ((said, message, command, who),) = member.calls
        assert said == "audited" and message == error["message"] and who == "mqtt"
        assert command.endswith("(group stack)")


@pytest.mark.parametrize(
    ("topic", "payload", "said"),
    [
        ("rotor/stack/lock", b"ON", "group stack has no lock: no rotator was locked"),
        # (an OFF was answered "no rotator was locked", read as: none of them is locked now)
        ("rotor/stack/lock", b"OFF", "group stack has no lock: no rotator was unlocked"),
        ("rotor/stack/lock", b"maybe", "group stack has no lock: no rotator changed its lock"),
        ("rotor/stack/park", b"PARK", "group stack takes a target and a stop only"),
        ("rotor/stack/option/jam", b"ON", "group stack takes a target and a stop only"),
        ("rotor/stack/track", b"sun", "group stack takes a target and a stop only"),
    ],
)
def test_a_rotators_command_sent_to_a_group_is_refused_on_its_error_topic_not_lost(
    topic: str, payload: bytes, said: str
) -> None:
    """An attack pass: ``G/lock ON`` (an operator's ACL lets them write ``rotor/+/lock``) was
    not even subscribed: nothing locked, nothing said, and whoever climbed the tower thought
    the stack was locked. Refused on ``G/error``, naming each member's own topic, and in each
    member's audit trail; nothing is carried out."""
    svc, pub, upper, lower = group_service()
    assert topic.rsplit("/", 1)[0] + "/+" in svc.subscriptions() or topic in svc.subscriptions()
    svc.on_message(topic, payload, False, "alice")
    (error,) = [json.loads(p) for t, p, _r in pub.take() if t == "rotor/stack/error"]
    assert error["kind"] == "refused" and error["message"].startswith(said)
    leaf = topic.removeprefix("rotor/stack/")
    assert f"rotor/upper/{leaf}, rotor/lower/{leaf}" in error["message"]
    for member in (upper, lower):
        ((done, message, _command, who),) = member.calls
        assert done == "audited" and message == error["message"] and who == "alice"


def test_a_group_stop_on_the_main_connection_stops_every_member_even_retained() -> None:
    svc, pub, upper, lower = group_service()
    svc.on_message("rotor/stack/stop", b"", False)
    svc.on_message("rotor/stack/stop", b"STOP", True)  # retained by mistake: stops, reported
    stop = Stop(Source.MQTT)
    assert upper.calls == [("submit", stop, "stop"), ("submit", stop, "stop 'STOP'")]
    assert lower.calls == upper.calls
    (error,) = [json.loads(p) for t, p, _r in pub.take() if t == "rotor/stack/error"]
    assert "published retained: executed" in error["message"]


def test_a_lane_group_stop_behind_a_flood_of_group_targets_holds_every_member() -> None:
    """lastword.py rules 2 and 9 for each member: the lane's group stop is carried out at once
    and holds both members; the flood of group targets published before it, read after it on
    the main connection while the hold lasts, is refused for each member (review 18: held,
    they waited for the copy to drop them, and a copy lost let them through); the target read
    after the main connection's copy waits under both holds (lastword.py rule 13) and goes out
    when the marker comes back. One marker for the group, one fresh one after its copy."""
    svc, pub, upper, lower = group_service()
    svc.on_lane_message("rotor/stack/stop", b"", False)
    markers = [m for m in pub.take() if m[0] == "rotor/bridge/fence"]
    assert len(markers) == 1
    for az in range(100, 110):  # published before the stop
        svc.on_message("rotor/stack/target", str(az).encode(), False)
    svc.on_message("rotor/stack/stop", b"", False)  # the main connection's copy
    svc.on_message("rotor/stack/target", b"50", False)  # published after it
    fresh = [m for m in pub.take() if m[0] == "rotor/bridge/fence"]
    assert len(fresh) == 1
    svc.on_message(fresh[0][0], fresh[0][1].encode(), False)  # back: both holds end
    stop = Stop(Source.MQTT)
    said = "target '50' (group stack)"
    for rot, offset in ((upper, 0), (lower, 180)):
        hold = rot.calls[0][-1]
        assert rot.calls[0] == ("submit", stop, "stop", hold) and hold >= 1
        flood = rot.calls[1:11]
        assert flood == [
            ("refused", HELD, f"target '{az}' (group stack)") for az in range(100, 110)
        ]
        assert rot.calls[11:] == [
            ("submit", stop, "stop"),
            ("submit", Target((50.0 + offset) % 360, None, M, az_either_end=offset != 0), said),
            ("release", int(fresh[0][1].split()[1])),
        ]
    # the lane's group stop held both members with the marker that went out: its return
    # would end both holds (as the fresh one did)
    assert markers[0][1].split()[1] == str(max(upper.calls[0][-1], lower.calls[0][-1]))


def test_the_lanes_late_copy_of_a_group_stop_the_main_connection_carried_out_is_an_echo() -> None:
    """lastword.py rule 4 for each member: main read it first; the lane's copy must not stop
    the group target published after it."""
    svc, pub, upper, lower = group_service()
    svc.on_message("rotor/stack/stop", b"", False)
    (lane_marker,) = [m for m in pub.take() if m[0] == "rotor/bridge/fence/lane"]
    svc.on_message("rotor/stack/target", b"10", False)
    svc.on_lane_message("rotor/stack/stop", b"", False)  # the echo, for both
    stop = Stop(Source.MQTT)
    assert [c[:2] for c in upper.calls] == [("submit", stop), ("submit", Target(10.0, None, M))]
    assert [c[:2] for c in lower.calls] == [
        ("submit", stop),
        ("submit", Target(190.0, None, M, az_either_end=True)),
    ]
    svc.on_lane_message(lane_marker[0], lane_marker[1].encode(), False)
    svc.on_lane_message("rotor/stack/stop", b"", False)  # a new one: carried out at once
    assert upper.calls[-1][:2] == ("submit", stop) and lower.calls[-1][:2] == ("submit", stop)


def test_a_replayed_retained_group_stop_under_mqtt_311_stops_once() -> None:
    svc, _pub, upper, lower = group_service()
    svc.retain_is_live(False)
    svc.on_lane_message("rotor/stack/stop", b"STOP", True)
    svc.on_message("rotor/stack/stop", b"STOP", True)
    assert len(upper.calls) == 1 and len(lower.calls) == 1


def test_the_groups_status_and_availability_follow_its_members() -> None:
    svc, pub, _upper, _lower = group_service()
    svc.publish_status("upper", RotatorStatus("upper", MotionState.IDLE, 10.0, available=True))
    assert pub.retained["rotor/stack/availability"] == "online"  # one member can hear a stop
    svc.publish_status("upper", RotatorStatus("upper"))
    assert pub.retained["rotor/stack/availability"] == "offline"
    svc.publish_status("other", RotatorStatus("other", MotionState.IDLE, 1.0, available=True))
    assert pub.retained["rotor/stack/availability"] == "offline"  # not a member
    svc.stop()
    assert "rotor/stack/availability" in pub.log[0]


def test_a_group_target_read_behind_a_members_halt_from_another_interface_skips_that_member() -> (
    None
):
    """service.py rule 11: the lower yagi stopped on the console, and a group target published
    before, read late: the others turn (groups.md), that member refuses it as older."""
    svc, _pub, upper, lower = group_service()
    svc.fence_asked("lower")
    svc.fence_carried("lower", lock=False)
    svc.on_message("rotor/stack/target", b"120", False, "alice")
    assert upper.calls == [("submit", Target(120.0, None, M), "target '120' (group stack)")]
    assert lower.calls == [("refused", FENCED, "target '120' (group stack)")]
