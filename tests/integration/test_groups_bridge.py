"""A group of two Rotor-EZ end to end (interfaces/mqtt/groups.py): real mosquitto, two emulated
Rotor-EZ on real ptys, real pyserial, the bridge. One ``G/target`` turns both (each with its offset:
the bytes on each wire, where each rotor really is, the retained bearings and ``G/status``); one
``G/stop`` while they turn stops both (a stop frame on each wire); a ``G/stop`` behind a flood
of group targets is carried out first on the stop lane, and not one target of the flood
reaches either wire after it (the main connection held still at its copy of the stop, as
tests/integration/test_last_word.py holds it); a retained ``G/target`` moves neither.
"""

from __future__ import annotations

import json
import time

from bridge.core.model import MotionState
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from tests.integration.test_last_word import bearings, main_held_at
from tests.support.mqtt import Message
from tests.support.rig import Rig
from tests.support.waiting import wait_until

GROUP = {"id": "stack", "name": "Stacked yagis", "rotators": ["upper", "lower"]}


def near(a: float, b: float, tol: float = 3.0) -> bool:
    return abs(a - b) <= tol


def stack(rig: Rig, upper: float = 10, lower: float = 190, speed: float = 40.0, **group: object):
    """Two Rotor-EZ, ``lower`` 180° from ``upper`` in the group, both ready."""
    up = rig.add("upper", emu={"start_az_deg": upper, "speed_deg_s": speed})
    low = rig.add("lower", emu={"start_az_deg": lower, "speed_deg_s": speed})
    rig.sections = {"groups": [{**GROUP, "offsets": {"lower": 180}, **group}]}
    return up, low


def test_one_group_target_turns_both_members_each_with_its_offset(rig: Rig) -> None:
    up, low = stack(rig)
    rig.start()
    rig.ready("upper")
    rig.ready("lower")
    rig.probe.wait_value("rotor/stack/availability", "online")
    rig.probe.publish("rotor/stack/target", "120")
    rig.arrived("upper", 120)
    rig.arrived("lower", 300)
    assert [f.data for f in up.frames(*BEARING_OUTCOMES)] == [b"AP1120\r"]
    assert [f.data for f in low.frames(*BEARING_OUTCOMES)] == [b"AP1300\r"]
    rig.probe.wait_value("rotor/upper/state", "idle", timeout_s=20)
    rig.probe.wait_value("rotor/lower/state", "idle", timeout_s=20)

    def settled(m: Message) -> bool:
        doc = json.loads(m.payload)
        members = doc["members"]
        return doc["state"] == "idle" and near(members["lower"]["bearing"] or 0, 300)

    status = json.loads(rig.probe.wait_for("rotor/stack/status", settled, timeout_s=20).payload)
    assert near(status["members"]["upper"]["bearing"], 120)
    assert near(status["bearing"], 120) and status["refused"] == {}
    retained = rig.retained()
    assert near(float(retained["rotor/upper/bearing"]), 120)
    assert near(float(retained["rotor/lower/bearing"]), 300)
    assert retained["rotor/stack/availability"] == b"online"


def test_a_members_group_limits_hold_on_its_way_not_only_at_its_target(rig: Rig) -> None:
    """A review: ``limits = { upper = [20, 340] }`` keeps the upper antenna out of 340..20; a
    450-degree rotor at 300, sent the group's 30, was sent M390 and swept through north."""
    up = rig.add("upper", model="gs232b-az-450", emu={"start_az_deg": 300})
    rig.add("lower", emu={"start_az_deg": 120})
    rig.sections = {"groups": [{**GROUP, "limits": {"upper": [20, 340]}}]}
    rig.start()
    rig.ready("upper")
    rig.ready("lower")
    rig.probe.publish("rotor/stack/target", "30")
    rig.arrived("upper", 30)
    assert [f.data for f in up.frames("move")] == [b"M030"]  # the long way, inside 20..340


def test_one_group_stop_while_turning_stops_both(rig: Rig) -> None:
    up, low = stack(rig, speed=20.0)
    rig.start()
    rig.ready("upper")
    rig.ready("lower")
    rig.probe.publish("rotor/stack/target", "300")  # upper 10 -> 300, lower 190 -> 120
    up.wait_for(lambda s: s.is_moving)
    low.wait_for(lambda s: s.is_moving)
    t = time.monotonic()  # before the stop, whose idles may come before the emulators are asked
    rig.probe.publish("rotor/stack/stop", "")
    up_still = up.wait_for(lambda s: not s.is_moving, 3)
    low_still = low.wait_for(lambda s: not s.is_moving, 3)
    assert up.frames("stop") and low.frames("stop")
    assert not near(up_still.az_deg, 300, 30) and not near(low_still.az_deg, 120, 30)
    rig.probe.wait_value("rotor/upper/state", "idle", timeout_s=10, after=t)
    rig.probe.wait_value("rotor/lower/state", "idle", timeout_s=10, after=t)
    assert [f.data for f in up.frames(*BEARING_OUTCOMES)] == [b"AP1300\r"]  # never again
    assert [f.data for f in low.frames(*BEARING_OUTCOMES)] == [b"AP1120\r"]


def test_a_group_stop_behind_a_flood_of_group_targets_is_never_overridden_by_them(
    rig: Rig,
) -> None:
    """The lane carries the group's stop out at once on both members and holds both; the
    flood published before it, handed on by the main connection before its own copy of the
    stop (held there until both rotors are idle again), never reaches a wire; the copy ends
    both holds, and a target published after it turns both."""
    up, low = stack(rig, speed=20.0)
    app = rig.start()
    rig.ready("upper")
    rig.ready("lower")
    rig.probe.publish("rotor/stack/target", "300")  # both turning: upper to 300, lower to 120
    up.wait_for(lambda s: s.is_moving)
    low.wait_for(lambda s: s.is_moving)
    with main_held_at(app, "rotor/stack/stop", b"") as held:
        stops = len(up.frames("stop")), len(low.frames("stop"))
        for az in range(120, 420):  # the flood
            rig.probe.publish("rotor/stack/target", str(az % 360), qos=0)
        rig.probe.publish("rotor/stack/stop", "")  # behind it
        # the main connection has handed the whole flood on and stops at its copy of the stop
        wait_until(held.is_set, 20, "the main connection is held at its copy of the stop")
        wait_until(lambda: app.mqtt._word.holding, 10, "the lane's group stop carried out")
        up.wait_until(lambda d, now: len(d.frames("stop")), lambda n: n > stops[0], 10)
        low.wait_until(lambda d, now: len(d.frames("stop")), lambda n: n > stops[1], 10)
        # both braked and read idle again (the bridge's own status: paho's thread, held, sends
        # nothing): a target not held would go out now
        for rid, emu in (("upper", up), ("lower", low)):
            emu.wait_for(lambda s: not s.is_moving and not s.in_brake_delay, 10)
            wait_until(lambda r=rid: rig.status(r).state is MotionState.IDLE, 10, f"{rid} idle")
        assert app.mqtt._word.holding  # both members wait for the main connection
    wait_until(lambda: not app.mqtt._word.holding, 20, "the main connection caught up")
    # not one target of the flood, ever
    assert bearings(up) == [b"AP1300\r"] and bearings(low) == [b"AP1120\r"]
    rig.probe.publish("rotor/stack/target", "40")  # published after the stop: obeyed
    rig.arrived("upper", 40)
    rig.arrived("lower", 220)
    assert bearings(up)[1:] == [b"AP1040\r"] and bearings(low)[1:] == [b"AP1220\r"]


def test_a_retained_group_target_moves_nothing(rig: Rig) -> None:
    up, low = stack(rig)
    rig.probe.publish("rotor/stack/target", "200", retain=True)  # there before the bridge
    rig.start()
    replayed = rig.probe.wait_for("rotor/stack/error", lambda m: b"retained" in m.payload)
    assert json.loads(replayed.payload)["kind"] == "refused"
    rig.ready("upper")
    rig.ready("lower")
    t = time.monotonic()
    rig.probe.publish("rotor/stack/target", "250", retain=True)  # published live, retained
    rig.probe.wait_for("rotor/stack/error", lambda m: b"'250'" in m.payload, after=t)
    rig.probe.publish("rotor/stack/target", b"", retain=True)  # deleted
    assert up.frames(*BEARING_OUTCOMES) == [] and low.frames(*BEARING_OUTCOMES) == []
    rig.probe.publish("rotor/stack/target", "40")  # and a live one still turns both
    rig.arrived("upper", 40)
    rig.arrived("lower", 220)


def test_a_lock_sent_to_a_groups_topic_is_refused_on_its_error_topic(rig: Rig) -> None:
    """An attack pass: ``rotor/stack/lock ON`` was not heard at all (a group has no lock), and
    nothing said so: the operator went up the tower thinking the stack was locked. It is
    refused on ``G/error``, which names each member's own lock topic, and nothing changes."""
    stack(rig)
    rig.start()
    rig.ready("upper")
    rig.ready("lower")
    t = time.monotonic()
    rig.probe.publish("rotor/stack/lock", "ON")
    said = json.loads(rig.probe.wait_for("rotor/stack/error", after=t).payload)
    assert said["kind"] == "refused" and said["command"] == "lock 'ON'"
    assert said["message"] == (
        "group stack has no lock: no rotator was locked; send it to each member's own topic: "
        "rotor/upper/lock, rotor/lower/lock"
    )
    retained = rig.retained()
    assert retained["rotor/upper/lock/state"] == retained["rotor/lower/lock/state"] == b"OFF"
