"""The wind-aware park end to end: wind readings published on a real mosquitto (as a weather
station or Home Assistant's statestream would), one running bridge (the App in-process) and an
emulated MD-01 on a real pty. Asserted: where the rotor really is (the emulator's truth), the
frames it received, and what the bridge publishes (R/status, R/error)."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import pytest

from tests.support import Mosquitto, Probe, retained_snapshot, wait_until
from tests.support.rig import Rig
from tests.support.state import kept
from tests.support.waiting import slow
from tests.test_homeassistant import render

TOPIC = "weather/station/wind"


def start(rig: Rig, emu: dict[str, Any] | None = None, **wind: Any) -> None:
    rig.add(
        "tower",
        "md01",
        emu={"start_az_deg": 120, **(emu or {})},  # 30 degrees from the storm's park: quick
        wind_topic=TOPIC,
        wind_unit="m/s",
        wind_park_above=20,  # 72 km/h
        wind_release_below=10,
        wind_park_az_deg=90,
        **wind,
    )
    rig.start()
    rig.ready("tower")


def error_after(rig: Rig, mark: int, kind: str) -> dict[str, Any]:
    msg = rig.probe.wait(
        lambda m: m.topic == "rotor/error" and json.loads(m.payload)["kind"] == kind,
        10,
        f"an error of kind {kind}",
        mark,
    )
    doc: dict[str, Any] = json.loads(msg.payload)
    return doc


def wind_of(rig: Rig, predicate: Any, start: int = 0) -> dict[str, Any]:
    """The wind block of the first status from message ``start`` on that satisfies it."""
    msg = rig.probe.wait(
        lambda m: m.topic == "rotor/status" and predicate(json.loads(m.payload).get("wind") or {}),
        10,
        "the wind in the status",
        start,
    )
    doc: dict[str, Any] = json.loads(msg.payload)["wind"]
    return doc


def test_a_storm_parks_refuses_motion_stop_works_and_calm_releases_after_the_hold(
    rig: Rig,
) -> None:
    start(rig, wind_hold_min=0.05)  # 3 s of calm (the hold, waited for below, is under test)
    rig.probe.publish(TOPIC, "5.0")
    wind_of(rig, lambda w: w.get("speed_kmh") == 18.0)  # m/s read as km/h

    rig.probe.publish(TOPIC, "25")  # 90 km/h: a storm
    rig.arrived("tower", 90.0, timeout_s=30)
    storm = wind_of(rig, lambda w: w.get("storm"))
    assert storm["speed_kmh"] == 90.0
    rig.probe.wait_for("rotor/status", lambda m: json.loads(m.payload)["parked"], 10)

    sets = len(rig.emu.frames("set"))
    mark = rig.probe.mark()
    rig.probe.publish("rotor/target", "200")
    refusal = error_after(rig, mark, "refused")
    assert refusal["message"] == "wind 90 km/h above 72: parked for the storm"
    rig.probe.publish("rotor/stop", "STOP")  # the stop always works
    rig.probe.wait_for(
        "rotor/status", lambda m: json.loads(m.payload)["last_command_source"] == "mqtt", 10
    )
    # the status is published before the stop's frame is written: wait for the frame itself
    wait_until(lambda: bool(rig.emu.frames("stop")), 10, "the stop on the wire")
    assert len(rig.emu.frames("set")) == sets

    mark = rig.probe.mark()
    rig.probe.publish(TOPIC, "3")  # calm: released only after the hold
    calm = wind_of(rig, lambda w: w.get("storm") and w.get("calm_since"), mark)
    assert calm["speed_kmh"] == 10.8

    def calm_reading_released() -> bool:
        """A calm reading every half second, as a station would, until one comes after the
        hold (3 s, the expiry under test): the clock alone never ends a storm."""
        rig.probe.publish(TOPIC, "2.5")
        last = rig.probe.last("rotor/status")
        return last is not None and json.loads(last.payload)["wind"]["storm"] is False

    wait_until(calm_reading_released, 15, "released by a calm reading after the hold", 0.5)
    rig.probe.publish("rotor/target", "150")
    rig.arrived("tower", 150.0, timeout_s=30)


def test_a_storm_reading_the_broker_kept_refuses_motion_but_moves_nothing(rig: Rig) -> None:
    """wind.py rule 6: a wind station dead for a week left its storm reading retained. The
    bridge starts: the replay refuses motion (the safe side) and parks nothing (no retained
    message moves a rotor: it turned the rotor to the park at every start); nor does a restart
    of the bridge. The station's first new storm reading parks it."""
    rig.probe.publish(TOPIC, "25", retain=True)  # 90 km/h, a week ago
    start(rig)
    wind = wind_of(rig, lambda w: w.get("storm"))
    assert wind["replayed"] is True and wind["speed_kmh"] == 90.0
    mark = rig.probe.mark()
    rig.probe.publish("rotor/target", "200")
    assert error_after(rig, mark, "refused")["message"] == (
        "wind 90 km/h above 72 (the last reading the broker kept): motion refused; the park "
        "waits for a new reading above 72"
    )
    rig.stop()
    # (after the stop and a round trip: the first run's own status after the refusal, taken
    # late, passed for the restart's)
    t_restart = rig.probe.caught_up()
    mark = rig.probe.mark()
    rig.start()
    rig.ready("tower", after=t_restart)
    assert wind_of(rig, lambda w: w.get("replayed"), mark)["storm"] is True
    assert rig.emu.frames("set") == [] and rig.emu.state().az_deg == 120.0
    rig.probe.publish(TOPIC, "24")  # the station is back: 86 km/h, new
    rig.arrived("tower", 90.0, timeout_s=30)
    assert wind_of(rig, lambda w: w.get("speed_kmh") == 86.4)["replayed"] is False


def shown(rig: Rig, entity: str) -> str:
    """What Home Assistant's ``entity`` (``platform/object id``) shows now: its retained
    discovery config's template on the retained R/status."""
    platform, oid = entity.split("/")
    config = retained_snapshot(rig.broker.port, "homeassistant/#")[
        f"homeassistant/{platform}/rotorbridge_rotor_r_tower/{oid}/config"
    ]
    status = retained_snapshot(rig.broker.port, "rotor/status")["rotor/status"]
    return render(json.loads(config)["value_template"], status.decode())


def storm_shown(rig: Rig) -> str:
    """What Home Assistant's binary sensor "Parked for the storm" shows now."""
    return shown(rig, "binary_sensor/storm")


def test_home_assistant_shows_no_park_for_a_storm_known_only_from_a_replay(rig: Rig) -> None:
    """wind.py rule 6 in Home Assistant: a storm known only from the reading the broker kept
    parks nothing, and "Parked for the storm" said on all the same while the rotor stood where
    it was (a review). It is on once a new reading parks it."""
    rig.probe.publish(TOPIC, "25", retain=True)  # 90 km/h, a week ago
    start(rig)
    wind_of(rig, lambda w: w.get("storm") and w.get("replayed"))
    assert storm_shown(rig) == "OFF"
    assert rig.emu.frames("set") == []
    mark = rig.probe.mark()
    rig.probe.publish(TOPIC, "24")  # the station is back: 86 km/h, new
    rig.arrived("tower", 90.0, timeout_s=30)
    wind_of(rig, lambda w: w.get("storm") and not w.get("replayed"), mark)
    assert storm_shown(rig) == "ON"


def test_home_assistant_shows_no_park_for_a_park_the_operator_stopped_short(rig: Rig) -> None:
    """wind.py rule 3 in Home Assistant: a STOP during the storm's park stops it where the rotor
    is, and "Parked for the storm" said on all the same (a review: the rotor stood 140 degrees
    from the park). A STOP once the rotor was seen at the park stops no park: it stays on."""
    start(rig, emu={"start_az_deg": 300})  # 150 degrees from the storm's park
    rig.probe.publish(TOPIC, "25")  # 90 km/h: the park begins
    wait_until(lambda: rig.emu.frames("set"), slow(10), "the park sent")
    assert storm_shown(rig) == "ON"  # parking
    mark = rig.probe.mark()
    rig.probe.publish("rotor/stop", "stop")
    wind_of(rig, lambda w: w.get("halted"), mark)
    assert storm_shown(rig) == "OFF"
    assert abs(rig.emu.state().az_deg - 90.0) > 20.0  # (stopped short, as the test needs)


def test_home_assistant_shows_no_park_for_a_storm_whose_park_waits_for_the_lock_off(
    rig: Rig,
) -> None:
    """wind.py rule 4 in Home Assistant: locked for tower work, a storm began; its park waits
    for the lock OFF, and "Parked for the storm" said on all the same while the rotor stood
    where the lock left it, 30 degrees from the park. It is on once the OFF parks it."""
    start(rig)
    mark = rig.probe.mark()
    rig.probe.publish("rotor/lock", "ON")
    rig.probe.wait(
        lambda m: m.topic == "rotor/status" and json.loads(m.payload)["locked"], 10, "locked", mark
    )
    mark = rig.probe.mark()
    rig.probe.publish(TOPIC, "25")  # 90 km/h: a storm, the rotor locked
    assert wind_of(rig, lambda w: w.get("storm"), mark)["waiting"] is True
    assert storm_shown(rig) == "OFF"
    assert rig.emu.frames("set") == []
    mark = rig.probe.mark()
    rig.probe.publish("rotor/lock", "OFF")
    rig.arrived("tower", 90.0, timeout_s=30)
    assert wind_of(rig, lambda w: w.get("storm") and not w.get("waiting"), mark)["halted"] is False
    assert storm_shown(rig) == "ON"


def test_a_stop_after_the_storms_park_was_reached_leaves_it_parked(rig: Rig) -> None:
    start(rig)
    rig.probe.publish(TOPIC, "25")  # 90 km/h: the park, 30 degrees away
    rig.arrived("tower", 90.0, timeout_s=30)
    rig.probe.wait_for("rotor/status", lambda m: json.loads(m.payload)["parked"], 10)
    polls = len(rig.emu.frames("status"))  # (the rotor seen at the park by the steps after it)
    rig.emu.wait_until(lambda d, now: len(d.frames("status")), lambda k: k >= polls + 2, 10)
    mark = rig.probe.mark()
    rig.probe.publish("rotor/stop", "stop")
    rig.probe.wait(
        lambda m: m.topic == "rotor/status" and json.loads(m.payload)["last_command_source"],
        10,
        "the stop in the status",
        mark,
    )
    assert wind_of(rig, lambda w: w.get("storm"), mark)["halted"] is False
    assert storm_shown(rig) == "ON"


def test_a_silent_wind_topic_is_reported_and_the_storm_goes_on(rig: Rig) -> None:
    start(rig, wind_silent_min=0.05)  # 3 s without a reading (the silence is under test)
    mark = rig.probe.mark()
    rig.probe.publish(TOPIC, "30")
    rig.arrived("tower", 90.0, timeout_s=30)
    silent = error_after(rig, mark, "wind")
    assert TOPIC in silent["message"] and "parked for the storm" in silent["message"]
    assert wind_of(rig, lambda w: w.get("silent"))["storm"] is True
    # Home Assistant's wind sensor: unknown while the topic is silent, not the last reading
    # as if it were the wind now (a review: 108 km/h shown for a station dead for hours)
    assert shown(rig, "sensor/wind") == "None"
    assert storm_shown(rig) == "ON"
    mark = rig.probe.mark()
    rig.probe.publish("rotor/target", "200")
    assert (
        error_after(rig, mark, "refused")["message"]
        == "wind 108 km/h above 72: parked for the storm"
    )
    mark = rig.probe.mark()
    rig.probe.publish(TOPIC, "29")  # the station is back
    wind_of(rig, lambda w: w.get("speed_kmh") == 104.4 and not w.get("silent"), mark)
    assert shown(rig, "sensor/wind") == "104.4"


def test_an_unreadable_wind_payload_changes_nothing(rig: Rig) -> None:
    start(rig)
    for junk in ("calm", "-3", "nan", '{"speed": 30}', ""):
        rig.probe.publish(TOPIC, junk)
    rig.probe.publish(TOPIC, "1")
    wind_of(rig, lambda w: w.get("speed_kmh") == 3.6)
    assert rig.emu.frames("set") == [] and not rig.status("tower").wind.storm  # type: ignore[union-attr]


def test_the_storms_park_turns_the_rotor_while_a_lease_is_held_and_the_wind_refuses_first(
    rig: Rig,
) -> None:
    start(rig)
    claim = json.dumps({"operator": "DL1ABC", "minutes": 30})
    rig.probe.publish("rotor/control/claim", claim)
    rig.probe.wait_for("rotor/control", lambda m: json.loads(m.payload)["holder"] == "DL1ABC")
    mark = rig.probe.mark()
    rig.probe.publish(TOPIC, "25")  # 90 km/h: the bridge's own move, the lease never judges it
    rig.arrived("tower", 90.0, timeout_s=30)
    msg = rig.probe.wait(
        lambda m: m.topic == "rotor/status" and json.loads(m.payload)["parked"], 10, "parked", mark
    )
    status = json.loads(msg.payload)
    assert status["last_command_source"] == "wind" and status["last_operator"] is None
    assert status["control"]["holder"] == "DL1ABC"  # still held
    # a target from someone else than the holder: the wind (safety) is said, not the lease
    mark = rig.probe.mark()
    rig.probe.publish("rotor/target", "200")
    assert error_after(rig, mark, "refused")["message"] == (
        "wind 90 km/h above 72: parked for the storm"
    )
    audit = rig.probe.wait(
        lambda m: m.topic == "rotor/audit" and "target" in json.loads(m.payload)["command"],
        10,
        "the refusal audited",
        mark,
    )
    assert (
        json.loads(audit.payload)["result"]
        == "refused: wind 90 km/h above 72: parked for the storm"
    )


def in_the_state_file(rig: Rig, key: str) -> None:
    wait_until(
        lambda: kept(rig.tmp / "state.json", "tower", key),
        10,
        f"{key} in the state file",
    )


def test_a_storm_outlives_a_restart_of_the_bridge_which_finishes_its_park(rig: Rig) -> None:
    """kept.py rule 4: only readings end a storm (wind.py rule 2), not a restart. The bridge
    stops in the storm's park (a slow rotor, 210 degrees from it): the park was never seen
    reached, so the next start sends it again. A reading between the two levels after the
    restart (50 km/h; park above 72, release below 36) ends nothing: motion stays refused."""
    start(rig, emu={"start_az_deg": 300, "az_speed_deg_s": 3.0}, wind_hold_min=1)
    rig.probe.publish(TOPIC, "25")  # 90 km/h, not retained: after the restart no reading says it
    wait_until(lambda: rig.emu.frames("set"), 10, "the park sent")
    in_the_state_file(rig, "storm")
    rig.stop()  # (its stop halts the rotor on its way: 70 s from the park at 3 degrees a second)
    assert rig.emu.state().az_deg > 150.0
    parks = len(rig.emu.frames("set"))
    t_restart = rig.probe.caught_up()
    mark = rig.probe.mark()
    rig.start()
    rig.ready("tower", after=t_restart)
    assert wind_of(rig, lambda w: w.get("storm"), mark)["storm"] is True
    # the storm's park is owed again after the restart: it is written once, to the same park,
    # whenever the first step takes it
    wait_until(lambda: len(rig.emu.frames("set")) == parks + 1, 10, "the park written again")
    rig.probe.publish(TOPIC, "14")  # 50 km/h: neither a storm nor a calm
    wind_of(rig, lambda w: 45 < (w.get("speed_kmh") or 0) < 55, mark)
    sets = len(rig.emu.frames("set"))
    assert sets == parks + 1 and rig.emu.frames("set")[-1].data == rig.emu.frames("set")[0].data
    before = rig.probe.mark()
    rig.probe.publish("rotor/target", "200")
    assert "parked for the storm" in error_after(rig, before, "refused")["message"]
    assert len(rig.emu.frames("set")) == sets


def test_a_storm_park_reached_is_not_done_again_by_a_restart(rig: Rig) -> None:
    """wind.py rule 7 across a restart (kept.py rule 4): the rotor was seen at the storm's
    park, then turned by hand at the controller's panel; the bridge restarted in the same storm
    leaves it where the hand put it (it turned it back to the park by itself), and the storm
    goes on."""
    start(rig, wind_hold_min=1)
    rig.probe.publish(TOPIC, "25")  # 90 km/h
    rig.arrived("tower", 90.0, timeout_s=30)
    in_the_state_file(rig, "storm_arrived")
    rig.emu.manual_rotate(200.0)
    wait_until(lambda: abs(rig.emu.state().az_deg - 200.0) < 1.0, 30, "turned by hand")
    rig.stop()
    sets = len(rig.emu.frames("set"))
    t_restart = rig.probe.caught_up()
    mark = rig.probe.mark()
    rig.start()
    rig.ready("tower", after=t_restart)
    assert wind_of(rig, lambda w: w.get("storm"), mark)["storm"] is True
    wind_of(rig, lambda w: w.get("off_park"), mark)  # (rule 10: judged from its first reading)
    before = rig.probe.mark()
    rig.probe.publish("rotor/target", "150")  # judged after the steps that would have parked
    refusal = error_after(rig, before, "refused")["message"]  # (wind.py rule 10: off its
    assert "turned off its park after reaching it" in refusal  # park, review 80: "parked")
    assert len(rig.emu.frames("set")) == sets
    assert abs(rig.emu.state().az_deg - 200.0) < 1.0


def test_a_storm_park_the_operator_stopped_is_not_done_again_by_a_restart(rig: Rig) -> None:
    """wind.py rule 3 across a restart (kept.py rule 4): the storm's park stopped by STOP stays
    stopped when the bridge comes back in the same storm; the storm itself goes on."""
    start(rig)
    rig.probe.publish(TOPIC, "25")  # 90 km/h: the park from 120 towards 90 begins
    wait_until(lambda: rig.emu.frames("set"), 10, "the park sent")
    rig.probe.publish("rotor/stop", "stop")
    wait_until(
        lambda: kept(rig.tmp / "state.json", "tower", "storm_halted"),
        10,
        "the stopped park in the state file",
    )
    rig.stop()
    where, sets = rig.emu.state().az_deg, len(rig.emu.frames("set"))
    t_restart = rig.probe.caught_up()
    mark = rig.probe.mark()
    rig.start()
    rig.ready("tower", after=t_restart)
    assert wind_of(rig, lambda w: w.get("storm"), mark)["storm"] is True
    before = rig.probe.mark()
    rig.probe.publish("rotor/target", "200")  # judged after the steps that would have parked
    said = error_after(rig, before, "refused")["message"]  # (it stands where the STOP left it)
    assert said.endswith("motion refused for the storm (a stop or lock ON stopped its park)")
    assert len(rig.emu.frames("set")) == sets
    assert abs(rig.emu.state().az_deg - where) < 1.0


def refused(rig: Rig, timeout_s: float) -> bool:
    """A target, and whether it was refused within ``timeout_s`` (for the wind)."""
    mark = rig.probe.mark()
    try:
        rig.probe.publish("rotor/target", "200")
        msg = rig.probe.wait(
            lambda m: m.topic == "rotor/error" and json.loads(m.payload)["kind"] == "refused",
            timeout_s,
            "a refusal",
            mark,
        )
    except (AssertionError, RuntimeError):  # not refused; the probe not connected again yet
        return False
    return "parked for the storm" in json.loads(msg.payload)["message"]


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_a_calm_the_broker_replays_after_a_restart_never_ends_the_storm(
    tmp_path: Path, protocol: str
) -> None:
    """wind.py rule 6, end to end: the station publishes retained (as weather stations and Home
    Assistant's statestream do). 90 km/h parks the rotor, one calm reading follows, then the
    station falls silent. The broker (persistence on) restarts after the hold and replays that
    calm reading: no new reading, so the storm goes on, targets stay refused and the rotor stays
    in its park. Then the station is back: its calm readings end the storm as ever."""
    conf = f"allow_anonymous true\nuser root\npersistence true\npersistence_location {tmp_path}/"
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf).start()
    probe = Probe(broker.port, "rotor/#")
    rig = Rig(tmp_path, broker, probe)
    rig.mqtt_extra = {"protocol": protocol}
    hold_s = 3.0
    try:
        start(rig, wind_hold_min=hold_s / 60, wind_silent_min=10)  # the hold, shorter
        probe.publish(TOPIC, "25", retain=True)  # 90 km/h
        rig.arrived("tower", 90.0, timeout_s=30)
        mark = probe.mark()
        probe.publish(TOPIC, "3", retain=True)  # a new calm reading (retained: not a replay)
        calm = wind_of(rig, lambda w: w.get("storm") and w.get("calm_since"), mark)
        assert calm["speed_kmh"] == 10.8
        t_calm = time.monotonic()
        # the scenario itself: the station is silent for longer than the hold
        time.sleep(max(0.0, t_calm + hold_s + 1.0 - time.monotonic()))
        sets = len(rig.emu.frames("set"))
        broker.restart()  # saved to its file, read back: the calm reading is replayed

        # targets until one is refused: the bridge is subscribed again, and the replay, sent
        # on subscribing, came before that target and was taken before the next one
        def refused_in_its_park() -> bool:
            assert len(rig.emu.frames("set")) == sets, "turned out of its storm park"
            return refused(rig, 1.0)

        wait_until(refused_in_its_park, 30, "a target refused after the restart")
        assert refused(rig, 10.0), "a target after the replay was not refused for the storm"
        last = probe.last("rotor/status")
        assert last is not None and json.loads(last.payload)["wind"]["storm"] is True
        assert len(rig.emu.frames("set")) == sets  # never turned out of its park
        assert abs(rig.emu.state().az_deg - 90.0) < 2.0

        def calm_reading_released() -> bool:
            probe.publish(TOPIC, "2.5", retain=True)  # the station is back
            last = probe.last("rotor/status")
            return last is not None and json.loads(last.payload)["wind"]["storm"] is False

        wait_until(calm_reading_released, 20, "released by new calm readings after the hold", 0.5)
        probe.publish("rotor/target", "150")
        rig.arrived("tower", 150.0, timeout_s=30)
    finally:
        rig.close()
        probe.close()
        broker.stop()


def test_the_bridges_end_leaves_a_storms_park_to_go_on(rig: Rig) -> None:
    """app.py rule 6: the end stops every rotor that may turn, but a storm's park goes on (a
    stop would keep it from being tried again after the restart: wind.py rule 3)."""
    start(rig, emu={"start_az_deg": 300})
    rig.probe.publish(TOPIC, "25")  # 90 km/h: a storm, the park 210 degrees away
    wait_until(lambda: rig.emu.state().is_moving, slow(10), "the park under way")
    stops = len(rig.emu.frames("stop"))
    rig.stop()
    assert len(rig.emu.frames("stop")) == stops  # no stop at the end
    assert not kept(rig.tmp / "state.json", "tower", "storm_halted")
    rest = rig.emu.wait_until(lambda d, now: d.state(now), lambda s: not s.is_moving, slow(30))
    assert abs((rest.az_deg - 90.0 + 180.0) % 360.0 - 180.0) <= 1.0, rest  # on to the park


def test_the_bridges_end_stops_a_turn_in_a_storm_known_only_from_a_replay(rig: Rig) -> None:
    """app.py rule 6 and wind.py rule 6: a storm known only from a replayed reading parks
    nothing, so a turn under way then is no storm's park: the end stops it like any."""
    start(rig, emu={"start_az_deg": 100, "az_speed_deg_s": 3.0})
    rig.probe.publish("rotor/target", "300")
    wait_until(lambda: rig.emu.state().is_moving, slow(10), "the turn under way")
    assert rig.app is not None
    rig.app.rotators[0].wind(90.0, replayed=True)  # as the feed hands a reading replayed
    wind_of(rig, lambda w: w.get("storm") and w.get("replayed"))
    stops = len(rig.emu.frames("stop"))
    rig.stop()  # the turn's stop before the end (read by the emulator's thread: waited for)
    wait_until(lambda: len(rig.emu.frames("stop")) > stops, 5, "the end's stop read")
    rest = rig.emu.wait_until(lambda d, now: d.state(now), lambda s: not s.is_moving, slow(10))
    assert rest.az_deg < 250.0, rest  # not on to 300
