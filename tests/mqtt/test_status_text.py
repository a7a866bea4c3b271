"""R/status as a rotator's StatusText makes it at every reading (interfaces/mqtt/payloads.py):
the text it keeps from one status to the next is the text a fresh ``json.dumps`` of the whole
document gives, over long runs of statuses each made of the last one's values (as
session/status.py makes them), where values change to equal ones of another type or sign too;
and a reading that only turns the rotor makes the kept part no more."""

from __future__ import annotations

import json
import random
from collections.abc import Sequence
from dataclasses import replace
from datetime import UTC, datetime
from itertools import pairwise

import pytest

from bridge.core.model import (
    AxisHealth,
    Control,
    FollowingInfo,
    MotionState,
    RotatorHealth,
    RotatorStatus,
    Target,
    TargetInfo,
    TrackingInfo,
    WindInfo,
)
from bridge.feature import status_blocks
from bridge.interfaces.mqtt import payloads as pl
from bridge.remote.readings import parse_status
from bridge.runtime.composite import merge
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite


def _iso(t: float) -> str:
    return datetime.fromtimestamp(t, UTC).isoformat(timespec="milliseconds")


def fresh(status: RotatorStatus, time_unix: float, has_elevation: bool, shows_raw: bool) -> str:
    """The document, whole, by json.dumps, in R/status's order (docs/mqtt.md): the blocks
    rendered as text go last, after the time."""
    doc: dict[str, object] = {"bearing": status.bearing_deg, "target": status.target_az_deg}
    if has_elevation:
        doc["elevation"] = status.elevation_deg
        doc["target_elevation"] = status.target_el_deg
    if status.controller_time is not None:
        doc["controller_time"] = status.controller_time
    if status.expected_end_unix is not None:
        doc["expected_end"] = _iso(status.expected_end_unix)
    if shows_raw:
        doc["raw_bearing"] = status.raw_bearing_deg
        doc["overlap"] = status.overlap
    if status.target_info is not None:
        doc["target_info"] = pl.target_info(status.target_info)
    doc["parked"] = status.parked
    last: dict[str, object] = {}
    for block in status_blocks():
        value = block.value(status)
        if value is not None:
            rendered = block.render(value)
            if block.rendered:
                last[block.key] = json.loads(str(rendered))
            else:
                doc[block.key] = rendered
    control = status.control
    doc.update(
        state=status.state.value,
        moving=status.moving,
        connected=status.connected,
        available=status.available,
        locked=status.locked,
        version=status.version,
        options=dict(sorted(status.options.items())),
        last_error=status.last_error,
        last_command_source=status.last_command_source,
        last_operator=status.last_operator,
        control=None
        if control is None
        else {"holder": control.operator, "until": _iso(control.until_unix)},
        estimated=status.estimated,
    )
    order = status.order
    if order is not None:
        doc["order"] = {
            "run": order.run,
            "taken": order.taken,
            "turn": order.turn,
            "lock": order.lock,
            "since": order.since,
        }
    doc["time"] = _iso(time_unix)
    doc.update(last)
    return json.dumps(doc, separators=(",", ":"))


T0 = 1_780_000_000.0
HEALTHS = [
    None,
    RotatorHealth(),
    RotatorHealth(az=AxisHealth(speed_up_deg_s=4.0, odometer_deg=12.5), moves=3),
    RotatorHealth(measured=False, warnings=("slow",), stall_azimuths_deg=(10.0, -0.0)),
]
TRACKINGS = [
    None,
    TrackingInfo("sun", "tracking", 120.5, 30.0, 121.0, 30.5),
    TrackingInfo("ISS", "waiting", aos_unix=T0 + 60, los_unix=T0 + 600, pass_track=((1.0, 2.0),)),
]
FOLLOWINGS = [None, FollowingInfo("wsjtx"), FollowingInfo("wsjtx", "long", "K1ABC", "FN42", 291.3)]
WINDS = [None, WindInfo(), WindInfo(55.0, True, T0 - 30, False, "storm")]
TARGETS = [None, TargetInfo(35.7, 139.7, 9000.0, 35.0, 215.0, "short", "PM95vq")]
#: equal to one another, each written its own way: a cache that compared values would mix them
SAME_NUMBER: list[object] = [1, 1.0, True, 0, 0.0, -0.0, False]
TEXTS = ["1.4S", "".join(["1.4", "S"]), "", None, 'naïve "quoted"\n']


def _change(rng: random.Random, s: RotatorStatus) -> RotatorStatus:
    """The next status: a reading (the bearing), and now and then anything else, each field to
    one of a few values (the same, equal but not the same, or another)."""
    bearing = round((s.bearing_deg or 0.0) + rng.choice([0.0, 0.8, -0.8, 1.0]), 2)
    fields: dict[str, object] = {"bearing_deg": bearing, "raw_bearing_deg": bearing}
    if rng.random() < 0.3:
        name = rng.choice(
            [
                "state", "target_az_deg", "elevation_deg", "target_el_deg", "connected",
                "available", "locked", "version", "options", "last_error",
                "last_command_source", "estimated", "controller_time", "expected_end_unix",
                "overlap", "target_info", "parked", "tracking", "tracking_ended", "following",
                "following_ended", "wind", "health", "last_operator", "control",
            ]
        )  # fmt: skip
        fields[name] = rng.choice(_choices(rng, name))
    if rng.random() < 0.5:  # the session copies the options at every status
        fields["options"] = dict(fields.get("options", s.options))  # type: ignore[call-overload]
    return replace(s, **fields)  # type: ignore[arg-type]


def _choices(rng: random.Random, name: str) -> Sequence[object]:
    match name:
        case "state":
            return list(MotionState)
        case "connected" | "available" | "locked" | "estimated" | "parked":
            return [True, False]
        case "target_az_deg" | "elevation_deg" | "target_el_deg":
            return [None, 0.0, -0.0, 12.5, 90.0, 359.99]
        case "expected_end_unix":
            return [None, T0 + 3.0, T0 + 3.0005]
        case "options":
            return [
                {},
                {"enable": rng.choice(SAME_NUMBER)},
                {"enable": rng.choice(SAME_NUMBER), "speed": rng.choice(SAME_NUMBER)},
                {"speed": 50.0, "enable": True},
                {"enable": True, "speed": 50.0},
            ]
        case "overlap":
            return [None, "cw", "ccw"]
        case "target_info":
            return TARGETS
        case "tracking":
            return TRACKINGS
        case "following":
            return FOLLOWINGS
        case "wind":
            return WINDS
        case "health":
            return HEALTHS
        case "control":
            return [None, Control("alice", T0 + 600), Control("bob", T0 + 600.25)]
        case "controller_time":
            return [None, "12:00:00", "".join(["12:00", ":00"])]
    return TEXTS  # version, last_error, last_command_source, *_ended, last_operator


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize(("has_elevation", "shows_raw"), [(False, False), (True, True)])
def test_the_kept_text_is_a_fresh_json_dumps_of_every_status(
    seed: int, has_elevation: bool, shows_raw: bool
) -> None:
    rng = random.Random(seed)
    text = pl.StatusText(has_elevation)
    status = RotatorStatus("r1", MotionState.MOVING, 10.0, connected=True, available=True)
    for n in range(1500):
        t = T0 + n * 0.2 + rng.choice([0.0, 0.0004, 0.9996])
        expected = fresh(status, t, has_elevation, shows_raw)
        assert text.render(status, t, shows_raw) == expected, n
        assert pl.status_json(status, t, has_elevation, shows_raw) == expected
        status = _change(rng, status)


def test_a_reading_that_only_turns_the_rotor_makes_the_rest_once(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each status made as the session makes it (the options copied, the rest the last
    status's): the rest of the document is made for the first only; a new value (even an
    equal one: True where 1 was) makes it again."""
    made = []
    rest = pl._status_rest

    def counted(*args: object) -> tuple[str, str]:
        made.append(1)
        return rest(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(pl, "_status_rest", counted)
    text = pl.StatusText(False)
    status = RotatorStatus("r1", MotionState.MOVING, 0.0, version="1.4S", options={"enable": 1})
    status = replace(status, health=HEALTHS[2], control=Control("alice", T0 + 600))
    for n in range(50):
        status = replace(status, bearing_deg=n * 0.8, options=dict(status.options))
        assert text.render(status, T0 + n, False) == fresh(status, T0 + n, False, False)
    assert len(made) == 1
    status = replace(status, options={"enable": True})
    assert '"options":{"enable":true}' in text.render(status, T0, False)
    assert len(made) == 2


def test_a_sessions_turning_readings_make_the_rest_once_per_state(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The statuses a real session emits (virtual time) while a Rotor-EZ turns from its front
    panel, no command taken: each is made of the last one's values but the bearing, the
    order's places too (an Order made anew at every status, the same places in it, made the
    rest again at every reading: some 8 of the 20 us publishing a reading cost warm,
    docs/performance.md). The rest is made for the first status and once per state the turn
    shows (moving, then idle), the text the fresh one every time."""
    made = []
    rest = pl._status_rest

    def counted(*args: object) -> tuple[str, str]:
        made.append(1)
        return rest(*args)  # type: ignore[arg-type]

    v = VirtualRotator("rotorez", emulator={"speed_deg_s": 4.0})
    v.run_for(3.0)  # online, idle, options read
    start = len(v.statuses)
    monkeypatch.setattr(pl, "_status_rest", counted)
    text = pl.StatusText(False)
    v.manual_rotate(90.0)
    v.run_until(lambda h: not h.truth().is_moving, 200.0, "the turn ends")
    v.run_for(3.0)
    turn = [s for _, s in v.statuses[start:]]
    assert len(turn) > 50  # (a reading each poll while it turned)
    for n, status in enumerate(turn):
        assert text.render(status, T0 + n, False) == fresh(status, T0 + n, False, False)
    assert len(made) <= 3, [s.state for s in turn]


def _rebuilds(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Each time R/status's rest is made again (payloads.py ``_status_rest``), counted."""
    made: list[int] = []
    rest = pl._status_rest

    def counted(*args: object) -> tuple[str, str]:
        made.append(1)
        return rest(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(pl, "_status_rest", counted)
    return made


def test_a_composites_turning_readings_make_the_rest_once_per_state(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A rotator of two boxes (runtime/composite.py), a Rotor-EZ's azimuth and a SatEL's
    elevation, each box saying its version, a wind topic read and the lease held, turned to
    200/40 in virtual time: its merged statuses are each made of the last one's values but the
    bearings. ``merge`` made a new Order, a new joined version (``1.4S / SatEL``) and a new
    wind at every merged status, the same in each: the rest of R/status was made again at
    every reading of either box (issue 39). It is made for the first status and once per state
    the turn shows, the text the fresh one every time."""
    wind = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 0}
    with VirtualComposite("rotorez", "satel", settings=wind) as v:
        v.run_until(lambda h: h.status.available, 10.0, "both boxes answer")
        v.mailbox.put_wind(20.0)
        v.mailbox.put_control(Control("DL1ABC", v.wall() + 1800))
        v._take()
        v.run_for(3.0)
        start = len(v.statuses)
        made = _rebuilds(monkeypatch)
        text = pl.StatusText(True)
        v.aim(Target(200.0, 40.0))
        v.run_until(lambda h: h.status.moving, 5.0, "the turn starts")
        v.run_until(lambda h: not h.status.moving, 200.0, "the turn ends")
        v.run_for(3.0)
        turn = [s for _, s in v.statuses[start:]]
    assert turn[-1].version == "1.4S / SatEL" and turn[-1].wind is not None
    assert turn[-1].control is not None and turn[-1].order is not None
    assert len(turn) > 50  # (a reading each poll of either box while it turned)
    for n, status in enumerate(turn):
        assert text.render(status, T0 + n, False) == fresh(status, T0 + n, True, False)
    # (the first status, then one per change of what the turn shows: braking, moving, the
    # SatEL's estimate in its slew, idle)
    shows = [(s.state, s.estimated) for s in turn]
    changes = 1 + sum(a != b for a, b in pairwise(shows))
    assert len(made) <= changes, (len(made), shows)


def test_a_storms_park_readings_make_the_rest_once_per_change(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A Rotor-EZ with a wind topic and the lease held, parked for a storm in virtual time
    (session/wind.py): the wind part made a new WindInfo at every status the session made,
    the same in each, so R/status's rest was made again at every reading of the wind's park
    turn, and of any turn (issue 39). It is made for the first status and once per change of
    what that rest is made of (the park's state, parked, the wind's park seen reached, which
    R/status does not show), the text the fresh one every time."""
    wind = {"wind_topic": "weather/wind", "wind_park_above": 60, "wind_park_az_deg": 200}
    v = VirtualRotator("rotorez", settings=wind, emulator={"speed_deg_s": 4.0})
    v.run_for(3.0)  # online, idle, options read
    v.mailbox.put_wind(20.0)
    v.mailbox.put_control(Control("DL1ABC", v.wall() + 1800))
    v._take()
    v.run_for(3.0)
    start = len(v.statuses)
    v.mailbox.put_wind(90.0)  # the storm: the rotor turns to its park at 200
    v._take()
    v.run_until(lambda h: h.status.moving, 10.0, "the park's turn starts")
    v.run_until(lambda h: h.status.parked, 200.0, "parked for the storm")
    v.run_for(3.0)
    turn = [s for _, s in v.statuses[start:]]
    assert turn[-1].wind is not None and turn[-1].wind.storm and turn[-1].control is not None
    assert len(turn) > 50  # (a reading each poll while it turned)
    # (what the rest is made of, by value: the status's own fields, its blocks, its options)
    rests = [(pl._REST_FIELDS(s), [b.value(s) for b in status_blocks()], s.options) for s in turn]
    changes = 1 + sum(a != b for a, b in pairwise(rests))
    made = _rebuilds(monkeypatch)
    text = pl.StatusText(False)
    for n, status in enumerate(turn):
        assert text.render(status, T0 + n, False) == fresh(status, T0 + n, False, False)
    assert len(made) <= changes, (len(made), changes, len(turn))


def test_a_remotes_readings_of_a_turn_make_the_rest_once_per_change(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The remote's console renders the station's R/status as it read it back
    (remote/readings.py ``parse_status``, each payload after the last): a Rotor-EZ with a wind
    topic and the lease held, turned to 200 in virtual time, its every status published. Each
    payload read all anew (new texts, lease, order, options, blocks) made the rest of the
    console's R/status again at every reading (issue 39). It is made for the first and once
    per change of what the rest says, the text the station's own every time."""
    wind = {"wind_topic": "weather/wind", "wind_park_above": 60, "wind_park_az_deg": 200}
    v = VirtualRotator(
        "rotorez",
        settings=wind,
        emulator={"speed_deg_s": 4.0},
        options={"endpoint": True, "overshoot": False},
    )
    v.run_for(3.0)  # online, idle, options read
    v.mailbox.put_wind(20.0)
    v.mailbox.put_control(Control("DL1ABC", v.wall() + 1800))
    v._take()
    v.run_for(3.0)
    start = len(v.statuses)
    v.target(200.0)
    v.run_until(lambda h: h.status.moving, 10.0, "the turn starts")
    v.run_until(lambda h: not h.status.moving, 200.0, "the turn ends")
    v.run_for(3.0)
    turn = [s for _, s in v.statuses[start:]]
    assert turn[-1].wind is not None and turn[-1].control is not None and turn[-1].options
    assert len(turn) > 50  # (a reading each poll while it turned)
    station = pl.StatusText(False)
    payloads = [station.render(s, T0 + n, False) for n, s in enumerate(turn)]
    # (the rest of each payload, as the station wrote it: what lies between parked and time)
    rests = [
        p[p.index('"parked"') : p.index('"time"')] + p[p.index('"time"') + 38 :] for p in payloads
    ]
    changes = 1 + sum(a != b for a, b in pairwise(rests))
    made = _rebuilds(monkeypatch)
    text = pl.StatusText(False)
    read = None
    for n, payload in enumerate(payloads):
        read = parse_status("v", payload.encode(), read)
        assert text.render(read, T0 + n, False) == payload
    assert len(made) <= changes, (len(made), changes, len(turn))


@pytest.mark.parametrize(("was", "now"), [(20, 20.0), (0.0, -0.0), (True, 1.0)])
def test_a_merged_status_keeps_no_value_that_writes_another_text(was: float, now: float) -> None:
    """``merge`` keeps the last merged wind only while it says the same to the letter
    (core/model.py ``kept_if_same``): an equal speed of another type or sign is another text
    on R/status (``20`` and ``20.0``, ``0.0`` and ``-0.0``), and the text is the fresh one."""
    before = merge(
        "v", RotatorStatus("v", wind=WindInfo(was)), RotatorStatus("v", wind=WindInfo(was))
    )
    after = merge(
        "v",
        RotatorStatus("v", wind=WindInfo(now)),
        RotatorStatus("v", wind=WindInfo(now)),
        before=before,
    )
    text = pl.StatusText(False)
    assert text.render(before, T0, False) == fresh(before, T0, False, False)
    assert text.render(after, T0, False) == fresh(after, T0, False, False)
    assert text.render(after, T0, False) != text.render(before, T0, False)
    same = merge(
        "v",
        RotatorStatus("v", wind=WindInfo(now)),
        RotatorStatus("v", wind=WindInfo(now)),
        before=after,
    )
    assert same.wind is after.wind  # (the very same: kept)
