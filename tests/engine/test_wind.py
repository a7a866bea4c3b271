"""The wind-aware park (session/wind.py): the part on its own, on read-only scenes and a fake
time; then wired into the session in virtual time against an emulated controller."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import pytest

from bridge.app import worker_config
from bridge.core.model import ErrorKind, MotionState, Source, Target
from bridge.session.parts import NOTHING, Proposal, Scene
from bridge.session.wind import WindPark
from bridge.settings import RotatorSettings
from bridge.sky import Body, Sky
from tests.engine.test_follow import STATION
from tests.engine.test_parts import rig, scene
from tests.engine.virtual import VirtualRotator

WIND = {
    "wind_topic": "weather/wind",
    "wind_park_above": 60,
    "wind_release_below": 40,
    "wind_hold_min": 10,
    "wind_silent_min": 15,
    "park_az_deg": 0,
    "wind_park_az_deg": 90,
}


def a_bug_once(monkeypatch: pytest.MonkeyPatch) -> list[bool]:
    """The wind's step raises once (a bug: the session resets the part, its rule 14); the
    list says whether it did."""
    real, raised = WindPark.step, []

    def once(self: WindPark, scene: Scene) -> Proposal:
        if not raised:
            raised.append(True)
            raise RuntimeError("a bug")
        return real(self, scene)

    monkeypatch.setattr(WindPark, "step", once)
    return raised


def park(**settings: Any) -> WindPark:
    return WindPark(rig("md01", **{**WIND, **settings}))


def test_without_a_wind_topic_it_does_nothing() -> None:
    part = WindPark(rig("md01"))
    part.reading(200.0, 0.0)
    assert part.step(scene(0.0)) is NOTHING and part.refusal() is None and part.info is None
    assert part.wakeup(0.0) is None


def test_a_storm_parks_once_ends_tracking_and_refuses_motion_with_the_reason() -> None:
    part = park()
    part.reading(30.0, 0.0)
    assert part.step(scene(0.0)) is NOTHING and part.refusal() is None
    part.reading(72.0, 5.0)
    proposal = part.step(scene(5.0))
    assert proposal.target is not None and proposal.target.source is Source.WIND
    assert proposal.target.park and proposal.target.az_deg == 90.0  # wind_park_az_deg
    assert proposal.ended == "wind 72 km/h above 60"  # tracking and following end with it
    assert part.refusal() == "wind 72 km/h above 60: parked for the storm"
    assert part.step(scene(6.0)).target is None  # once per storm
    info = part.info
    assert info is not None and info.storm and info.speed_kmh == 72.0


def test_the_storm_ends_only_after_the_hold_below_the_release_level() -> None:
    part = park()
    part.reading(70.0, 0.0)
    part.step(scene(0.0))
    part.reading(50.0, 10.0)  # below the park level, above the release: still a storm
    assert part.step(scene(700.0)).target is None and part.storm
    part.reading(30.0, 700.0)  # calm from here
    assert part.wakeup(700.0) == 700.0 + 900.0  # the silence: the hold ends with a reading
    part.step(scene(1000.0))
    part.reading(45.0, 1000.0)  # a gust at the release level: the hold starts again
    part.reading(20.0, 1100.0)
    part.reading(25.0, 1650.0)
    part.step(scene(1650.0))
    assert part.storm  # 550 s of calm, not 600
    part.step(scene(1700.0))
    assert part.storm  # 600 s passed, but no reading says the wind stayed calm
    part.reading(22.0, 1700.0)
    part.step(scene(1700.0))
    assert not part.storm and part.refusal() is None


def test_a_park_owed_and_not_sent_is_said_waiting_with_what_it_waits_for() -> None:
    """Rule 9 (review 63): a park owed says what it waits for, never "parked", until sent."""
    part = park()
    part.reading(72.0, 0.0)  # the storm begins before the controller ever answered
    assert part.info is not None and part.info.waiting
    said = "wind 72 km/h above 60: motion refused for the storm (its park waits for "
    assert part.refusal() == said + "the controller to answer)"
    assert part.step(scene(1.0, locked=True)) is not None and part.info.waiting
    assert part.refusal() == said + "the lock OFF)"
    proposal = part.step(scene(2.0))  # the lock OFF: the park goes
    assert proposal.target is not None and not part.info.waiting
    part.held_back(True)  # taken, but waiting under a STOP's hold (rule 8)
    assert part.info.waiting and part.refusal() == said + (
        "the hold of a STOP or lock ON sent before the storm)"
    )
    part.held_back(False)
    assert part.refusal() == "wind 72 km/h above 60: parked for the storm"


def test_a_stop_or_the_lock_stops_the_park_and_it_is_not_tried_again_in_this_storm() -> None:
    part = park()
    part.reading(80.0, 0.0)
    part.halted()  # a stop came with the reading
    assert part.step(scene(0.0)).target is None
    assert part.refusal() is not None  # motion is refused all the same
    locked = park()
    locked.reading(80.0, 0.0)
    assert locked.step(scene(0.0, locked=True)).target is None  # the lock first
    assert locked.step(scene(1.0)).target is not None  # then unlocked: the park is still owed


def test_a_silent_topic_is_reported_once_and_keeps_the_storm() -> None:
    part = park()
    part.reading(80.0, 0.0)
    part.step(scene(0.0))
    assert part.wakeup(0.0) == 900.0
    silent = part.step(scene(900.0))
    assert silent.error is not None and silent.error.kind is ErrorKind.WIND
    assert "weather/wind" in silent.error.message and "parked for the storm" in silent.error.message
    assert part.step(scene(5000.0)) is NOTHING  # once
    assert part.storm and part.info is not None and part.info.silent  # never released by it
    part.reading(10.0, 5000.0)
    assert part.info is not None and not part.info.silent


def test_a_topic_silent_during_the_calm_never_ends_the_storm() -> None:
    """One calm reading and then nothing (the weather station lost its power in the storm):
    no reading says the wind stayed calm, so the hold is never over by the clock alone; after
    the silence the calm starts again from the next reading."""
    part = park()
    part.reading(80.0, 0.0)
    part.step(scene(0.0))
    part.reading(20.0, 100.0)  # calm, then the station goes quiet
    for now in (700.0, 1000.0, 5000.0):  # the hold (600 s) and the silence (900 s) pass
        part.step(scene(now))
        assert part.storm and part.refusal() is not None, now
    part.reading(15.0, 5000.0)  # back: the calm counts from here, not from 100 s
    part.step(scene(5000.0))
    assert part.storm
    part.reading(10.0, 5300.0)
    part.step(scene(5300.0))
    assert part.storm  # 300 s of readings, not 600
    part.reading(12.0, 5600.0)
    part.step(scene(5600.0))
    assert not part.storm and part.refusal() is None


def test_before_any_reading_silence_counts_from_the_start() -> None:
    part = park()
    assert part.step(scene(100.0)) is NOTHING
    reported = part.step(scene(1000.0))
    assert reported.error is not None and "no storm" in reported.error.message


def test_m_s_thresholds_are_converted() -> None:
    settings = {**WIND, "wind_unit": "m/s", "wind_park_above": 20, "wind_release_below": 10}
    cfg = worker_config(RotatorSettings(id="w", model="md01", port="/x", **settings))
    assert cfg.wind is not None
    assert (cfg.wind.park_above_kmh, cfg.wind.release_below_kmh) == (72.0, 36.0)


@pytest.mark.parametrize(
    ("settings", "field"),
    [
        ({"keep_out": [[80, 100]]}, "wind_park_az_deg: azimuth 90 is in the keep-out sector"),
        ({"az_max_deg": 60}, "wind_park_az_deg: azimuth 90 outside the limits"),
        ({"wind_park_az_deg": None, "park_az_deg": 90, "keep_out": [[80, 100]]}, "park_az_deg"),
    ],
)
def test_a_storm_park_the_judge_would_refuse_is_a_settings_error(
    settings: dict[str, Any], field: str
) -> None:
    """settings/wind.py rule 1: said when the settings are read, naming the field, not refused
    in the storm with the antenna facing the wind."""
    with pytest.raises(ValueError, match=field):
        RotatorSettings(id="w", model="md01", port="/x", **{**WIND, **settings})
    off = {**WIND, "wind_topic": None, **settings}  # the wind park unused: not judged
    if off.get("park_az_deg") != 90:
        RotatorSettings(id="w", model="md01", port="/x", **off)


def test_the_park_refused_by_the_judge_is_reported_and_motion_stays_refused() -> None:
    """Rule 5, a safeguard: the settings refuse a park the judge would (above)."""
    cfg = rig("md01", **WIND)
    part = WindPark(replace(cfg, pointing=replace(cfg.aim, keep_out=((80.0, 100.0),))))
    part.reading(80.0, 0.0)
    proposal = part.step(scene(0.0))
    assert proposal.target is None and proposal.error is not None
    assert proposal.error.message.startswith("wind park refused")
    assert part.refusal() is not None


# -- in the session, in virtual time ------------------------------------------------------------
def windy(**settings: Any) -> VirtualRotator:
    v = VirtualRotator(
        "md01",
        settings={"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0, **WIND, **settings},
        emulator={"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0, "start_az_deg": 200},
        sky=Sky(52.5, 13.4),
    )
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    return v


def wind(v: VirtualRotator, kmh: float) -> None:
    v.mailbox.put_wind(kmh)
    v._take()


def test_the_storm_parks_the_rotor_refuses_targets_and_stop_and_lock_still_work() -> None:
    with windy() as v:
        wind(v, 30.0)
        v.track(Body.sun())
        wind(v, 75.0)
        v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
        assert abs(v.truth().az_deg - 90.0) <= 0.5
        assert v.status.tracking is None and v.status.tracking_ended == "wind 75 km/h above 60"
        assert v.status.wind is not None and v.status.wind.storm
        assert v.status.last_command_source == "wind"
        v.target(200.0)
        assert v.errors("refused")[-1].message == "wind 75 km/h above 60: parked for the storm"
        v.run_for(30.0)
        assert abs(v.truth().az_deg - 90.0) <= 0.5  # nothing moved
        v.lock(True)  # the lock always works
        assert v.status.locked
        v.lock(False)
        v.stop()  # and the stop
        assert v.status.last_command_source == "mqtt"


def test_a_stop_during_the_storms_park_stops_it_and_it_is_not_tried_again() -> None:
    with windy() as v:
        wind(v, 90.0)
        v.run_until(lambda h: h.truth().is_moving, 10, "the park starts")
        v.stop()
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "stopped")
        where = v.truth().az_deg
        assert abs(where - 90.0) > 5.0
        v.run_for(120.0)
        assert abs(v.truth().az_deg - where) <= 0.5  # the stop holds
        assert v.status.wind is not None and v.status.wind.storm  # motion still refused


def test_after_the_hold_the_storm_is_over_and_targets_are_taken_again() -> None:
    with windy(wind_hold_min=1) as v:
        wind(v, 90.0)
        v.run_until(lambda h: h.status.parked, 60, "parked")
        wind(v, 10.0)
        v.run_for(50.0)
        v.target(150.0)
        assert v.errors("refused")[-1].message.endswith("parked for the storm")
        v.run_for(15.0)  # the minute of calm is over...
        assert v.status.wind is not None and v.status.wind.storm
        wind(v, 12.0)  # ...and a reading says so
        assert v.status.wind is not None and not v.status.wind.storm
        v.target(150.0)
        v.run_until(lambda h: abs(h.truth().az_deg - 150.0) <= 0.5, 60, "150")


def test_auto_park_leaves_the_storms_park_alone() -> None:
    with windy(park_after_idle_s=30) as v:
        wind(v, 90.0)
        v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
        v.run_for(600.0)
        assert abs(v.truth().az_deg - 90.0) <= 0.5  # not turned to park_az_deg 0


def test_the_calm_reading_that_ends_the_storm_does_not_auto_park_at_once() -> None:
    """feed.py rule 2, autopark.py rule 1: a reading never moves the rotor anywhere but to the
    storm's park. The calm reading that ended a storm whose park a STOP had stopped short let
    auto-park's quiet spell, long over, park the rotor that instant (an attack pass: 200 to 0
    at the storm's end, no command): the storm's end starts a new spell, as unlocking does."""
    with windy(park_after_idle_s=30, wind_hold_min=1) as v:
        wind(v, 90.0)
        v.run_until(lambda h: h.truth().is_moving, 10, "the park starts")
        v.stop()
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "stopped")
        where = v.truth().az_deg
        v.run_for(120.0)  # auto-park's spell is long over: the storm holds it back
        wind(v, 10.0)
        v.run_for(61.0)
        wind(v, 12.0)  # the hold is over: the storm ends with this reading
        assert v.status.wind is not None and not v.status.wind.storm
        ended = v.now
        v.run_for(25.0)
        assert abs(v.truth().az_deg - where) <= 0.5  # not turned by the reading
        assert v.status.last_command_source == "mqtt"
        v.run_until(lambda h: h.status.last_command_source == "auto-park", 30, "auto-park")
        assert v.now - ended >= 30.0  # a whole quiet spell after the storm's end


def test_a_wind_part_that_raises_keeps_the_storm(monkeypatch: pytest.MonkeyPatch) -> None:
    with windy() as v:
        wind(v, 90.0)
        v.run_until(lambda h: h.status.parked, 60, "parked")

        def broken(self: WindPark, scene: object) -> None:
            raise RuntimeError("a bug")

        monkeypatch.setattr(WindPark, "step", broken)
        v.run_for(2.0)
        assert v.errors("internal")  # each step, as long as the bug is there
        v.command(Target(200.0))
        assert v.errors("refused")[-1].message.endswith("parked for the storm")


def test_a_wind_part_that_raises_after_a_stop_does_not_park_again(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Rule 3 through a reset (session.py rule 14): the operator's STOP of the storm's park
    stays in effect when the wind's part is reset after a bug (the reset owed the park again,
    and the rotor went to it)."""
    with windy() as v:
        wind(v, 90.0)
        v.run_until(lambda h: h.truth().is_moving, 10, "the park starts")
        v.stop()
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "stopped")
        where = v.truth().az_deg
        raised = a_bug_once(monkeypatch)
        v.run_for(60.0)
        assert raised and v.errors("internal")
        assert abs(v.truth().az_deg - where) <= 0.5
        assert v.status.wind is not None and v.status.wind.storm


def test_a_replayed_calm_never_ends_a_storm_nor_says_the_station_is_back() -> None:
    """Rule 6, as weather stations and Home Assistant's statestream publish (retained): a storm,
    one calm reading, then the station falls silent; the broker restarts after the hold and
    replays that same calm reading. It is no new reading: the storm goes on (a hold shorter
    than the silence, so only the replay could end it)."""
    part = park(wind_hold_min=5, wind_silent_min=15)
    part.reading(80.0, 0.0)
    assert part.step(scene(0.0)).target is not None
    part.reading(10.0, 60.0)  # the last reading the station sends
    part.step(scene(60.0))
    part.reading(10.0, 60.0 + 300.0 + 10.0, replayed=True)  # the broker's restart, after the hold
    part.step(scene(370.0))
    assert part.storm and part.refusal() is not None
    part.step(scene(60.0 + 900.0))  # the station is silent, and said so
    part.reading(10.0, 1000.0, replayed=True)  # a reconnect: replayed again
    part.step(scene(1000.0))
    info = part.info
    assert info is not None and info.silent and info.storm and info.speed_kmh == 10.0
    part.reading(12.0, 1100.0)  # the station is back: the calm starts from here
    part.reading(11.0, 1100.0 + 299.0)
    part.step(scene(1399.0))
    assert part.storm
    part.reading(11.0, 1100.0 + 300.0)
    part.step(scene(1400.0))
    assert not part.storm


def test_a_replayed_reading_may_start_a_storm_or_its_hold_again_and_shows_until_a_new_one() -> None:
    """Rule 6's safe side: the last known wind after a restart of the bridge refuses motion if
    it was a storm, and parks nothing until a new reading says so; during a calm, a replayed
    gust starts the hold again."""
    part = park(wind_hold_min=5)
    part.reading(20.0, 0.0, replayed=True)  # the first state: shown, no storm
    part.step(scene(0.0))
    info = part.info
    assert info is not None and info.speed_kmh == 20.0 and not info.storm
    part.reading(75.0, 1.0, replayed=True)
    assert part.step(scene(1.0)).target is None  # no retained message moves a rotor
    assert part.refusal() == (
        "wind 75 km/h above 60 (the last reading the broker kept): motion refused; the park "
        "waits for a new reading above 60"
    )
    info = part.info
    assert info is not None and info.storm and info.replayed
    part.reading(55.0, 5.0)  # new, but not above the park level: still no park
    assert part.step(scene(5.0)).target is None and part.storm
    part.reading(72.0, 6.0)  # new, above it: the park, as rule 1 says
    proposal = part.step(scene(6.0))
    assert proposal.target is not None and proposal.target.az_deg == 90.0
    assert part.refusal() == "wind 72 km/h above 60: parked for the storm"
    assert part.info is not None and not part.info.replayed
    part.reading(10.0, 10.0)  # new: the calm begins
    part.reading(45.0, 200.0, replayed=True)  # at the release level: the hold starts again
    part.reading(10.0, 320.0)
    part.step(scene(320.0))
    assert part.storm  # 310 s after the calm began, but it began again at 320
    info = part.info
    assert info is not None and info.speed_kmh == 10.0  # the newest new reading
    part.reading(10.0, 620.0)
    part.step(scene(620.0))
    assert not part.storm


def test_a_stop_in_a_storm_known_only_from_a_replay_holds_back_no_later_park() -> None:
    """Rules 3 and 6: a storm known only from the broker's replay has no park to stop; a STOP
    then, and the station's new storm reading later, parks (as it would after a restart of the
    bridge between them, which keeps no such storm: a review)."""
    part = park()
    part.reading(90.0, 0.0, replayed=True)
    assert part.step(scene(0.0)).target is None
    part.halted()  # the operator's STOP
    part.reading(80.0, 30.0)
    proposal = part.step(scene(30.0))
    assert proposal.target is not None and proposal.target.az_deg == 90.0
    assert part.storm and not part.park_halted


def test_a_wind_part_reset_in_a_storm_known_only_from_a_replay_parks_nothing(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Rule 6 through a reset (session.py rule 14): the part rebuilt after a bug took the
    replayed storm for one whose park was owed, and the rotor went to it."""
    with windy() as v:
        v.mailbox.put_wind(90.0, replayed=True)
        v._take()
        v.run_for(2.0)
        raised = a_bug_once(monkeypatch)
        v.run_for(60.0)
        assert raised and v.errors("internal")
        assert abs(v.truth().az_deg - 200.0) <= 0.5, v.truth()  # not turned to the park, 90
        assert v.status.wind is not None and v.status.wind.storm and v.status.wind.replayed


def test_the_silence_of_a_storm_known_only_from_a_replay_says_nothing_was_parked() -> None:
    """Rules 4 and 6: a wind station dead with a storm reading left retained: its silence was
    reported as "keeping the state it had (parked for the storm)" while the rotor stood where
    it was, never parked."""
    part = park()
    part.reading(80.0, 0.0, replayed=True)
    assert part.step(scene(0.0)).target is None
    silent = part.step(scene(900.0))
    assert silent.target is None and silent.error is not None
    assert silent.error.message == (
        "no wind reading on weather/wind for 15 min: keeping the state it had (a storm known "
        "only from the reading the broker kept: motion refused, nothing parked)"
    )


def test_the_silence_of_a_storm_whose_park_was_stopped_says_it_was_stopped() -> None:
    """Rules 3 and 4, a review: the operator's STOP stopped the storm's park, and the wind
    station's silence then was reported as "keeping the state it had (parked for the storm)"
    while the rotor stood where the STOP left it."""
    part = park()
    part.reading(80.0, 0.0)
    assert part.step(scene(0.0)).target is not None
    part.halted()  # the operator's STOP
    silent = part.step(scene(900.0))
    assert silent.target is None and silent.error is not None
    assert silent.error.message == (
        "no wind reading on weather/wind for 15 min: keeping the state it had (a storm whose "
        "park a stop or lock ON stopped: motion refused)"
    )


def test_the_silence_of_a_storm_begun_under_the_lock_says_nothing_was_parked() -> None:
    """Rule 4: the rotator locked for tower work, a storm began (its park waits for the lock
    OFF) and the wind station fell silent: the report said "keeping the state it had (parked
    for the storm)" while the rotor stood where the lock left it. The park goes at the OFF."""
    with windy() as v:
        wind(v, 30.0)
        v.lock(True)
        wind(v, 90.0)
        v.run_for(16 * 60.0)  # wind_silent_min is 15
        assert [e.message for e in v.errors("wind")] == [
            "no wind reading on weather/wind for 15 min: keeping the state it had (a storm whose "
            "park waits for the lock OFF: motion refused, nothing parked)"
        ]
        assert abs(v.truth().az_deg - 200.0) <= 0.5, v.truth()  # where the lock left it
        v.lock(False)
        v.run_until(lambda h: h.status.parked, 60, "parked once the lock is OFF")
        assert abs(v.truth().az_deg - 90.0) <= 0.5, v.truth()


def test_a_stop_after_the_rotor_reached_the_storms_park_leaves_it_said_parked() -> None:
    """Rules 1, 3 and 4: a STOP or lock ON after the rotor was seen at the storm's park stops
    no park (the status's ``halted`` is false then): the refusal and the silence still say the
    rotor is parked, not that a stop stopped its park (a review: locked for tower work at the
    park, every target was refused saying the park had been stopped)."""
    with windy() as v:
        wind(v, 75.0)
        v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
        v.run_for(5.0)
        v.lock(True)  # tower work, the rotor at its park
        v.lock(False)
        v.stop()
        v.target(200.0)
        assert v.errors("refused")[-1].message == "wind 75 km/h above 60: parked for the storm"
        assert v.status.wind is not None and v.status.wind.arrived
        v.run_for(16 * 60.0)  # wind_silent_min is 15
        assert [e.message for e in v.errors("wind")] == [
            "no wind reading on weather/wind for 15 min: keeping the state it had (parked for "
            "the storm)"
        ]
        assert abs(v.truth().az_deg - 90.0) <= 0.5, v.truth()


def test_a_storm_known_only_from_a_replay_ends_tracking_and_the_calm_turns_nothing() -> None:
    """Rules 1 and 6: a storm reading the broker kept (replayed after a reconnect) refuses
    motion; it ends tracking too. An attack pass: R/status said "tracking" through such a storm
    while the rotor stood still, and when live calm readings ended it, tracking turned the
    rotor again by itself."""
    with windy(wind_hold_min=1) as v:
        wind(v, 30.0)
        v.track(Body.sun())
        v.run_until(lambda h: h.state is MotionState.IDLE and h.now > 30.0, 120, "on the sun")
        assert v.status.tracking is not None
        v.mailbox.put_wind(90.0, replayed=True)
        v._take()
        v.run_for(5.0)
        assert v.status.tracking is None
        assert v.status.tracking_ended == "wind 90 km/h above 60 (the last reading the broker kept)"
        where, since = v.truth(), v.now
        wind(v, 20.0)  # the calm, live
        v.run_for(70.0)
        wind(v, 20.0)
        v.run_for(5.0)
        assert v.status.wind is not None and not v.status.wind.storm  # the storm is over
        v.run_for(900.0)  # the sun moves some degrees meanwhile
        assert v.frames("set", "set: clamped", since=since) == []
        assert (v.truth().az_deg, v.truth().el_deg) == (where.az_deg, where.el_deg)
        assert v.status.tracking is None


def test_a_target_still_waiting_when_a_storm_begins_never_goes_out() -> None:
    """Rules 1 and 6: every motion command is refused from the storm's start, one accepted
    before it but not sent yet too. A Rotor-EZ's new target waits for the brake after the stop
    that ends the turn before; a storm known only from a replay (a reconnect of the broker)
    sends no park to replace it, and the target went out 6 s into the storm, while the status
    said motion was refused (an attack pass: AP1300 written, the rotor turned to 300)."""
    with VirtualRotator(
        "rotorez", settings=WIND, emulator={"start_az_deg": 200.0}, sky=Sky(52.5, 13.4)
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(30.0)
        v.run_until(lambda h: h.truth().is_moving, 10, "turning to 30")
        v.target(300.0)  # the turn is stopped first; 300 waits for the brake
        assert v.session.targets.pending is not None
        v.mailbox.put_wind(90.0, replayed=True)
        v._take()
        assert v.status.wind is not None and v.status.wind.storm
        t = v.now  # (the turn to 30 may have been written at this very time: not after it)
        v.run_for(60.0)
        after = [f for f in v.frames("executed", since=t) if f.time_s > t]
        assert not after  # no target reached the controller
        assert v.truth().az_deg > 150.0  # where the stop left it, not on to 300 (nor 30)
        dropped = v.errors("refused")[-1]
        assert dropped.message.startswith("target dropped: wind 90 km/h above 60 (the last")
        assert dropped.command == "target az 300"


@pytest.mark.parametrize("replayed", [False, True])
def test_a_following_target_waiting_when_a_storm_begins_is_ended_unsaid(replayed: bool) -> None:
    """Rule 1: the storm ends following, and the target it was waiting to send with it: its
    ``following_ended`` says why. Only a target someone sent is refused on R/error (a cold
    review: a WSJT-X target waiting for a Rotor-EZ's brake was refused there as 'target az
    296.065', a command nobody sent)."""
    with VirtualRotator(
        "rotorez",
        settings=WIND,
        emulator={"start_az_deg": 200.0},
        sky=Sky(52.5, 13.4),
        follow=STATION,
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_until(lambda h: h.truth().is_moving, 10, "following JA1ABC")
        v.heard("W1AW", "FN31")  # the turn is stopped first; FN31's bearing waits for the brake
        assert v.session.targets.pending is not None
        t = v.now
        v.mailbox.put_wind(90.0, replayed=replayed)
        v._take()
        v.run_for(60.0)
        assert v.errors("refused", since=t) == []
        assert v.status.following is None
        assert (v.status.following_ended or "").startswith("wind 90 km/h above 60")
        assert not any(b"296" in f.data for f in v.frames(since=t))  # FN31 never went out


def test_a_target_lost_on_the_line_is_not_tried_again_in_a_storm() -> None:
    """Rule 1: from the storm's start every motion command is refused, and rule 6's storm
    sends nothing. A user's target whose frame was lost on the line gets one try more
    (controller.py rule 11) once a reading shows it did not move the rotor; a storm known
    only from a replay (a broker's reconnect) began meanwhile, so nothing waited for
    ``_storm`` to drop, and the try more went out in the storm: the rotor turned to 300 while
    the status said motion was refused for it (a cold review)."""
    with VirtualRotator(
        "easycomm2",
        settings={"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0, **WIND},
        emulator={"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0, "start_az_deg": 200},
        sky=Sky(52.5, 13.4),
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_for(3.0)
        v.drop_writes(b"AZ300.0 EL0.0\n")  # the target's frame lost on the line
        v.target(300.0, 0.0)
        v.run_for(0.3)
        assert v.session.targets.pending is None  # it went out (and was lost)
        t = v.now
        v.mailbox.put_wind(90.0, replayed=True)
        v._take()
        assert v.status.wind is not None and v.status.wind.storm
        v.run_for(30.0)
        assert [w.data for w in v.writes if w.t >= t and w.data.startswith(b"AZ3")] == []
        assert abs(v.truth().az_deg - 200.0) <= 0.5  # not turned in the storm
        dropped = v.errors("refused", since=t)
        assert [e.command for e in dropped] == ["target az 300 el 0"]
        assert "not sent again: wind 90 km/h above 60" in dropped[0].message


def test_a_satels_late_slew_is_stopped_and_not_sent_again_in_a_storm() -> None:
    """Rule 1: a SatEL's slew whose report is late is stopped, and its target put back to go
    again (slew.py rule 4). A storm known only from a replay began during the slew: it sends
    nothing, so nothing waited for ``_storm`` to drop, and the target put back went out in
    the storm: the rotor turned on to 200 while the status said motion was refused (a
    review). It is not sent again, and R/error says so once, naming the storm."""
    fast = {"az_speed_deg_s": 30, "el_speed_deg_s": 15}  # its slews outlast their report bound
    with VirtualRotator("satel", settings={**fast, **WIND}) as v:
        v.run_until_state(MotionState.IDLE, 30)
        t = v.now
        v.target(200.0, 20.0)
        v.run_until(lambda h: h.truth().slewing, 5, "slewing to 200/20")
        v.mailbox.put_wind(90.0, replayed=True)
        v._take()
        assert v.status.wind is not None and v.status.wind.storm and v.status.wind.replayed
        v.run_until(lambda h: any(e.kind == "stopped" for e in h.device.events), 120, "stopped")
        stood = v.truth()
        v.run_for(120.0)
        slews = [f.data for f in v.frames("slew", since=t)]
        assert slews == [b"p200 20\r"]  # not a second time, in the storm
        assert (v.truth().az_deg, v.truth().el_deg) == (stood.az_deg, stood.el_deg)
        assert 0 < stood.az_deg < 200  # where the stop left it
        said = v.errors(since=t)
        assert [(e.kind, e.command) for e in said] == [("refused", "target az 200 el 20")]
        assert said[0].message.startswith("no report from the controller")
        storm = "wind 90 km/h above 60 (the last reading the broker kept)"
        assert f"stopping it to ask where it is; its target is not sent again: {storm}" in (
            said[0].message
        )
        assert v.state is MotionState.IDLE and v.status.target_az_deg is None


def test_auto_parks_target_waiting_when_a_storm_begins_is_dropped_unsaid() -> None:
    """Rule 1: a target the bridge itself was about to send when a storm begins ends with the
    storm unsaid, as tracking's and following's do; only a command someone sent is refused on
    R/error. Auto-park's park, waiting for a Rotor-EZ's fresh reading (targets.py rule 7), was
    refused there as 'target az 0', a command nobody sent (a cold review)."""
    with VirtualRotator(
        "rotorez",
        settings={**WIND, "park_after_idle_s": 30},
        emulator={"start_az_deg": 200.0},
        sky=Sky(52.5, 13.4),
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")

        def parking(h: VirtualRotator) -> bool:
            pending = h.session.targets.pending
            return pending is not None and pending.source is Source.AUTO_PARK

        v.run_until(parking, 60, "auto-park's park waits for a reading")
        t = v.now
        v.mailbox.put_wind(90.0, replayed=True)
        v._take()
        v.run_for(30.0)
        assert v.errors("refused", since=t) == []
        assert not any(b"AP1" in f.data or b"AP0" in f.data for f in v.frames(since=t))
        assert abs(v.truth().az_deg - 200.0) <= 0.5


def test_a_storms_park_without_an_elevation_holds_the_elevation_where_it_reads() -> None:
    """session/targets.py rule 9: the storm's park names the azimuth alone (no park
    elevation set); a turn to 300/40 under way when the storm began kept its elevation
    target, the half of a target the storm refused motion for, and the elevation turned on to
    40 beside the park (a GS-232B sent ``W090 040``; in a composite, the elevation box alone:
    a closing note). It now stops where the park found it."""
    slow_el = {"az_speed_deg_s": 10.0, "el_speed_deg_s": 2.0}
    with VirtualRotator(
        "gs232b",
        settings={**slow_el, **WIND},
        emulator={**slow_el, "start_az_deg": 200},
        sky=Sky(52.5, 13.4),
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(300.0, 40.0)
        v.run_until(lambda h: h.truth().el_deg >= 10.0, 30, "the elevation under way")
        t = v.now
        wind(v, 90.0)
        v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
        parks = [w for w in v.sent(since=t) if w.startswith(b"W")]
        assert parks and all(not w.endswith(b" 040\r") for w in parks), parks
        assert 10.0 <= v.truth().el_deg <= 14.0, v.truth()
        assert abs(v.truth().az_deg - 90.0) <= 1.0


@pytest.mark.parametrize(
    ("model", "el_min", "start_el", "sent_as"),
    [("easycomm2", None, -0.5, b"AZ90.0 EL0.0\n"), ("gs232b", 10.0, 0.0, b"W090 000\r")],
)
def test_a_storms_park_without_an_elevation_holds_it_where_the_box_can_be_sent(
    model: str, el_min: float | None, start_el: float, sent_as: bytes
) -> None:
    """session/targets.py rule 9: the elevation a storm's park leaves out is held where it
    reads, inside what the controller can be sent, not inside the user's el_min_deg. An
    Easycomm box reading -0.5 (a reading below the horizon is a reading there) was sent
    nothing, -0.5 being nothing it can be sent: the session's step failed at every try while
    the storm blew. A dish resting at 0 below a limit of 10 (docs/homeassistant.md names the
    case) was lifted to 10, an axis the park leaves as it is, off its rest in the storm."""
    extra = {} if el_min is None else {"el_min_deg": el_min}
    with VirtualRotator(
        model,
        settings={**WIND, **extra},
        emulator={"start_az_deg": 200, "start_el_deg": start_el},
        sky=Sky(52.5, 13.4),
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        t = v.now
        wind(v, 90.0)
        v.run_until(lambda h: h.status.parked, 120, "parked for the storm")
        v.run_for(30)
        assert v.errors("internal", since=t) == []
        sets = [w for w in v.sent(since=t) if w[:1] in b"AW" and w != b"AZ EL\n"]
        assert sets == [sent_as], sets  # (not the queries)
        assert abs(v.truth().az_deg - 90.0) <= 1.0, v.truth()
        assert v.truth().el_deg <= 0.5, v.truth()
        assert el_min is None or v.truth().el_deg == start_el, v.truth()  # at rest, untouched
