"""Tracking (session/tracking.py) in virtual time: the session, an emulated controller and a
fake clock whose wall time starts at a fixed instant (SUN_EPOCH, SAT_EPOCH): every run, at any
time of day, judges the same sky. Positions are checked
against references computed in the test by other means (tests/support/sky.py: a published
low-precision solar formula, and the sgp4 package with our own frame transforms), never by
the library the bridge uses."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path

import pytest

from bridge.core.model import MotionState, Source, Target
from bridge.features.tracking import tracking_state
from bridge.session.tracking import STALE_DAYS, Track
from bridge.sky import Body, Pass, Sky, SkyError
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import (
    Answer,
    LookupQuestion,
    PassQuestion,
    PositionsQuestion,
    Question,
    answer,
)
from tests.engine.virtual import VirtualRotator
from tests.support.sky import sgp4_altaz, sun_altaz, synthetic_tle, tle_with_pass

# The sky of these tests is fixed: positions, passes and the sun's speed across it are those at
# these instants, so a run at any time of day judges the same sky (the rotor-EZ test failed at
# two times of day in sixty, when the sun at the chosen station barely moved in azimuth).
SUN_EPOCH = 1_781_000_000.0  # 2026-06-09 10:13 UTC
SAT_EPOCH = 1_781_020_000.0  # the synthetic satellites' epoch, and their passes' search start


def sun_up_somewhere(t_unix: float, lo: float = 35.0, hi: float = 60.0) -> tuple[float, float]:
    """A station where the sun stands between ``lo`` and ``hi`` degrees at ``t_unix``."""
    for lat in (0.0, 30.0, -30.0, 50.0, -50.0):
        for lon in range(-180, 180, 5):
            az, el = sun_altaz(lat, float(lon), t_unix)
            if lo <= el <= hi and 20.0 <= az <= 340.0:
                return lat, float(lon)
    raise AssertionError("the sun is up somewhere")


def pointing(az_deg: float, el_deg: float) -> tuple[float, float]:
    """Where an az/el rotor really points: past 90 of elevation it looks the other way."""
    if el_deg > 90.0:
        return (az_deg + 180.0) % 360.0, 180.0 - el_deg
    return az_deg % 360.0, el_deg


def off_deg(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def test_the_sun_is_followed_within_2_degrees_on_an_md01() -> None:
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall)
    with VirtualRotator(
        "md01",
        sky=Sky(lat, lon),
        wall_epoch_s=wall,
        emulator={"az_speed_deg_s": 2.0, "el_speed_deg_s": 1.0},
        settings={"az_speed_deg_s": 2.0, "el_speed_deg_s": 1.0},
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.sun())
        assert v.status.tracking is not None and v.status.tracking.body == "sun"

        def on_the_sun(h: VirtualRotator) -> bool:
            sun = sun_altaz(lat, lon, h.wall())
            az, el = pointing(h.truth().az_deg, h.truth().el_deg)
            return off_deg(az, sun[0]) <= 2.0 and abs(el - sun[1]) <= 2.0

        v.run_until(on_the_sun, 400, "the rotor reaches the sun")
        worst = 0.0
        end = v.now + 600.0  # ten minutes of rotor time, sampled every second
        while v.now < end:
            v.run_for(1.0)
            sun = sun_altaz(lat, lon, v.wall())
            az, el = pointing(v.truth().az_deg, v.truth().el_deg)
            worst = max(worst, off_deg(az, sun[0]), abs(el - sun[1]))
        assert worst <= 2.0, worst
        info = v.status.tracking
        assert info is not None and info.phase == "tracking"
        assert off_deg(info.azimuth_deg or 0.0, sun_altaz(lat, lon, v.wall())[0]) < 0.5
        assert v.status.last_command_source == Source.TRACKING.value


BERLIN = (52.52, 13.29)  # JO62qm's centre


def a_pass_that(across_north: bool) -> tuple[str, str, float, float]:
    """A synthetic satellite (epoch: SAT_EPOCH) with a pass over Berlin whose azimuth does (or
    does not) run across the north: the first fit starting on a half-hour grid from then."""
    now = SAT_EPOCH
    for k in range(48):
        tle = tle_with_pass(*BERLIN, now + 1800.0 * k, min_max_el_deg=25, max_max_el_deg=60)
        if crosses_north(tle) == across_north:
            return tle
    raise AssertionError("no such pass in a day")


def crosses_north(tle: tuple[str, str, float, float]) -> bool:
    line1, line2, aos, los = tle
    steps = int(los - aos) // 5
    track = [sgp4_altaz(line1, line2, *BERLIN, aos + 5.0 * i)[0] for i in range(steps + 1)]
    return any(abs(b - a) > 180.0 for a, b in zip(track, track[1:], strict=False))


@pytest.fixture(scope="module")
def a_pass() -> tuple[str, str, float, float]:
    return a_pass_that(across_north=True)  # the harder one: the overlap takes it on a SPID


@pytest.fixture(scope="module")
def a_pass_clear_of_north() -> tuple[str, str, float, float]:
    return a_pass_that(across_north=False)


def fly(
    model: str, tle: tuple[str, str, float, float], settings: dict[str, object] | None = None
) -> tuple[VirtualRotator, list[tuple[float, float, float]]]:
    """Track the pass from 10 minutes before its AOS to 60 s after its LOS; the rotor's
    pointing error against the independent SGP4 every second of the pass (t, az err, el err)."""
    line1, line2, aos, los = tle
    start_wall = aos - 600.0
    v = VirtualRotator(
        model,
        sky=Sky(*BERLIN),
        wall_epoch_s=start_wall,
        emulator={"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0} if model != "satel" else {},
        settings={"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0, **(settings or {})}
        if model != "satel"
        else dict(settings or {}),
    )
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.track(Body.satellite("TESTSAT", line1, line2))
    errors: list[tuple[float, float, float]] = []
    v.run_until(lambda h: h.wall() >= aos, 700, "AOS")
    while v.wall() < los:
        v.run_for(1.0)
        sat_az, sat_el = sgp4_altaz(line1, line2, *BERLIN, v.wall())
        truth = v.truth()
        el_now = truth.el_deg if truth.el_deg is not None else sat_el
        az, el = pointing(truth.az_deg, el_now)
        errors.append((v.wall(), off_deg(az, sat_az), abs(el - sat_el)))
    v.run_for(60.0)
    return v, errors


def test_a_satellite_pass_is_prepositioned_followed_within_3_degrees_and_parked(
    a_pass: tuple[str, str, float, float],
) -> None:
    line1, line2, aos, los = a_pass
    v, errors = fly("md01", a_pass, {"park_az_deg": 0, "park_el_deg": 0, "track_at_los": "park"})
    with v:
        # pre-positioned: the statuses in the minute before AOS say it waited, still, at AOS
        before = [s for t, s in v.statuses if aos - 60 <= v.wall_epoch_s + t < aos]
        phases = {s.tracking.phase if s.tracking else None for s in before}
        assert before and phases == {"waiting"}, phases
        aos_az, _ = sgp4_altaz(line1, line2, *BERLIN, aos)
        last = before[-1]
        assert last.state is MotionState.IDLE
        assert off_deg(last.bearing_deg or 0.0, aos_az) <= 3.0, (last.bearing_deg, aos_az)
        # during the pass, skipping the first seconds (the body rises at the horizon's edge)
        worst_az = max(e[1] for e in errors)
        worst_el = max(e[2] for e in errors)
        assert worst_az <= 3.0 and worst_el <= 3.0, (worst_az, worst_el)
        # parked after LOS
        v.run_until(lambda h: h.status.parked, 200, "parked after the pass")
        assert v.status.tracking is not None  # still tracking: waiting for the next pass


def test_a_satel_is_never_sent_input_while_it_slews_during_a_pass(
    a_pass_clear_of_north: tuple[str, str, float, float],
) -> None:
    v, errors = fly("satel", a_pass_clear_of_north)
    with v:
        assert v.device.misuse_frames() == []
        # step-wise: never stopped to be redirected (the stop at connect comes before tracking)
        assert [f for f in v.frames("stop") if f.time_s > 1.0] == []
        slews = v.frames("slew")
        assert len(slews) >= 5, slews  # it did follow, a step at a time
        # step-wise, with the default step (its tolerance, 3) and its speeds, each target the
        # nearest of its rotors' ten-degree steps (satel.py rule 7): within half a step and
        # its lag, 7 degrees (a pass across the north costs a 0..360 rotor whose elevation ends
        # at 90 one unwind)
        assert max(e[1] for e in errors) <= 7.0 and max(e[2] for e in errors) <= 7.0


def test_a_satel_whose_elevation_limit_is_between_its_steps_tracks_at_the_highest_step() -> None:
    """Rule 6 on a SatEL turned as built (ten-degree steps: protocols/satel.py rule 7) with
    ``el_max_deg = 75`` and the sun at some 79 degrees: the elevation is held at 70, the
    highest step inside the limit. An attack pass: held at 75, which goes out as 80, past the
    limit, every target was refused, and the rotor never moved, in azimuth either."""
    lat, lon, wall = 23.0, 14.0, SUN_EPOCH  # the sun at about 88 / 79
    assert sun_altaz(lat, lon, wall)[1] > 75
    emulator, settings = {"step_deg": 10}, {"el_max_deg": 75.0}
    sky = Sky(lat, lon)
    with VirtualRotator(
        "satel", sky=sky, wall_epoch_s=wall, emulator=emulator, settings=settings
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.sun())
        v.run_until(lambda h: not h.truth().is_moving and h.truth().el_deg == 70.0, 120, "at 70")
        v.run_for(60)
        assert v.status.tracking is not None and v.status.tracking.phase == "tracking"
        assert v.errors() == []
        assert off_deg(v.truth().az_deg, sun_altaz(lat, lon, v.wall())[0]) <= 5.0 + 3.0


def test_a_pass_across_the_north_is_flown_flipped_on_a_0_to_360_rotor(
    a_pass: tuple[str, str, float, float],
) -> None:
    """Rule 4: with the azimuth limited to 0..360 and elevation to 180, a pass across the
    north is flown with elevation past 90 and azimuth + 180: no unwind mid-pass."""
    limits = {"az_min_deg": 0, "az_max_deg": 360, "el_min_deg": 0, "el_max_deg": 180}
    v, errors = fly("rot2prog", a_pass, limits)
    with v:
        during = [
            s.tracking for _t, s in v.statuses if s.tracking and s.tracking.phase == "tracking"
        ]
        assert during and all(info.flip for info in during)
        # half the 3 degree step either side, a Rot2Prog's whole-degree cut and its lag
        assert max(e[1] for e in errors) <= 3.5 and max(e[2] for e in errors) <= 3.5
        sets = v.frames("set", "set: clamped")
        azimuths = [int(f.data[1:5]) / f.data[5] - 360 for f in sets]
        travel = sum(abs(b - a) for a, b in zip(azimuths, azimuths[1:], strict=False))
        assert travel < 200.0, azimuths  # across the sky once, never round the stop


def test_a_rotor_ez_follows_the_sun_in_azimuth_without_ever_retargeting_while_turning() -> None:
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    with VirtualRotator("rotorez", sky=Sky(lat, lon), wall_epoch_s=wall) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.sun())
        v.run_until(
            lambda h: off_deg(h.truth().az_deg, sun_altaz(lat, lon, h.wall())[0]) <= 3.0,
            200,
            "on the sun's azimuth",
        )
        worst = 0.0
        for _ in range(3600):  # an hour: the sun moves some 10 degrees in azimuth
            v.run_for(1.0)
            worst = max(worst, off_deg(v.truth().az_deg, sun_altaz(lat, lon, v.wall())[0]))
        # half the step either side, plus the Rotor-EZ's own tolerance: it may stop 3 short
        assert worst <= 1.5 + 3.0, worst
        executed = v.frames("executed")
        assert len(executed) >= 2, executed  # it moved on with the sun
        never = ("ignored: brake delay", "ignored: re-target while turning (stopped)")
        assert v.frames(*never) == []


@pytest.mark.parametrize("lon", [20.0, 21.0, 23.0])
def test_a_hy_gain_rotor_swings_once_round_its_stop_as_the_sun_crosses_south(lon: float) -> None:
    """A Rotor-EZ's Hy-Gain rotor, its stop at south (emulator rule 12), follows the sun across
    its transit: once the sun is past 180, the one way there is the whole way round through
    north, a turn the motion machine must not take for a pass (motion.py rule 5,
    ``along_travel``: 179 and 181 are a whole turn apart). An investigation: at most such
    stations the turn was stopped a few degrees in as 'turned on past its target', tracking
    ended, and the rotor was left 20-40 degrees off the sun."""
    lat, wall = 50.0, SUN_EPOCH  # the sun crosses south 10 to 20 minutes in
    emulator = {"start_az_deg": 165.0, "stop_at_south": True}
    with VirtualRotator("rotorez", sky=Sky(lat, lon), wall_epoch_s=wall, emulator=emulator) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        t0 = v.now
        v.track(Body.sun())
        v.run_until(lambda h: sun_altaz(lat, lon, h.wall())[0] > 185.0, 3600, "the sun past 185")
        v.run_for(120.0)  # the swing (some 60 s at 6 degrees a second) and a step or two after
        assert v.status.tracking is not None and v.status.tracking_ended is None
        assert v.errors() == []
        assert off_deg(v.truth().az_deg, sun_altaz(lat, lon, v.wall())[0]) <= 1.5 + 3.0
        turns = [e for e in v.device.events if e.time_s > t0 and e.kind in ("move", "arrived")]
        took = [b.time_s - a.time_s for a, b in zip(turns, turns[1:], strict=False)]
        swings = [s for s, a in zip(took, turns, strict=False) if a.kind == "move" and s > 30]
        assert len(swings) == 1  # the crossing's one, some 350 degrees; no second one back
        assert all(a.kind != b.kind for a, b in zip(turns, turns[1:], strict=False))  # none cut
        never = ("ignored: brake delay", "ignored: re-target while turning (stopped)")
        assert v.frames(*never) == []


@pytest.mark.parametrize("how", ["off", "stop", "lock", "manual target"])
def test_tracking_ends_on_off_stop_lock_and_a_manual_target(how: str) -> None:
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall)
    with VirtualRotator("rot2prog", sky=Sky(lat, lon), wall_epoch_s=wall) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.sun())
        v.run_for(5.0)
        assert v.status.tracking is not None
        if how == "off":
            v.track(None)
        elif how == "stop":
            v.stop()
        elif how == "lock":
            v.lock(True)
        else:
            v.aim(Target(10.0, 10.0))
        v.run_for(2.0)
        assert v.status.tracking is None
        assert v.status.tracking_ended == {"manual target": "mqtt target"}.get(how, how)
        sent = len(v.sent())
        v.run_for(120.0)
        if how != "manual target":  # nothing more is sent but polls
            frames = v.frames("set", "set: clamped")
            assert all(f.time_s < v.now - 115 for f in frames), frames
        assert len(v.sent()) >= sent


def test_a_pass_through_a_keep_out_sector_holds_and_says_so_once(
    a_pass: tuple[str, str, float, float],
) -> None:
    line1, line2, aos, los = a_pass
    mid_az, _ = sgp4_altaz(line1, line2, *BERLIN, (aos + los) / 2)
    sector = [round(mid_az - 15) % 360, round(mid_az + 15) % 360]
    # (kept to 0..90 of elevation: a rotor that can flip flies the pass around the sector,
    # test_a_rotor_that_can_flip_flies_a_pass_around_a_keep_out_sector)
    v, _errors = fly("rot2prog", a_pass, {"keep_out": [sector], "el_max_deg": 90})
    with v:
        refusals = [e for e in v.errors("refused") if "tracking TESTSAT" in e.message]
        assert len(refusals) == 1, refusals
        assert "keep-out" in refusals[0].message
        for f in v.frames("set", "set: clamped"):
            assert not _in_sector(f.data, sector)


def test_a_rotor_that_can_flip_flies_a_pass_around_a_keep_out_sector(
    a_pass: tuple[str, str, float, float],
) -> None:
    """Attack 19 (tracking.py rule 4): the flip weighs what the judge refuses, so the pass
    through the sector above is flown flipped, clear of it, on a Rot2Prog whose elevation
    reaches 180: nothing refused, nothing sent into the sector, the satellite followed."""
    line1, line2, aos, los = a_pass
    mid_az, _ = sgp4_altaz(line1, line2, *BERLIN, (aos + los) / 2)
    sector = [round(mid_az - 15) % 360, round(mid_az + 15) % 360]
    v, errors = fly("rot2prog", a_pass, {"keep_out": [sector]})
    with v:
        during = [s.tracking for t, s in v.statuses if aos <= v.wall_epoch_s + t < los]
        assert during and all(i is not None and i.flip for i in during)
        assert not [e for e in v.errors("refused") if "tracking TESTSAT" in e.message]
        for f in v.frames("set", "set: clamped"):
            assert not _in_sector(f.data, sector)
        assert max(e[1] for e in errors) <= 3.5  # (observed: 2.2 degrees at most)


def _in_sector(frame: bytes, sector: list[int]) -> bool:
    """A Rot2Prog set frame (W, four ASCII digits of pulses, the pulses per degree, ...)."""
    az = int(frame[1:5]) / frame[5] - 360
    start, end = sector
    a = az % 360
    return start <= a <= end if start <= end else a >= start or a <= end


def test_eight_rotors_tracking_one_body_from_one_station_share_its_pass() -> None:
    """Benchmark finding: each of 8 rotors starting to track the sun searched its pass again
    (70-95 ms each, on the thread that serves every serial line)."""
    sky = Sky(*BERLIN)
    t = SUN_EPOCH
    first = sky.next_pass(Body.sun(), t)
    assert all(sky.next_pass(Body.sun(), t + dt) is first for dt in (0.0, 1.0, 60.0))
    assert first is not None
    assert sky.next_pass(Body.sun(), first.los_s + 1.0) is not first  # the next one is new


def _tracking_the_sun(
    model: str = "rot2prog", wall: float | None = None
) -> tuple[VirtualRotator, float, float]:
    wall = SUN_EPOCH if wall is None else wall
    lat, lon = sun_up_somewhere(wall)
    v = VirtualRotator(
        model,
        sky=Sky(lat, lon),
        wall_epoch_s=wall,
        emulator={"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0},
        settings={"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0},
    )
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.track(Body.sun())

    def on_it(h: VirtualRotator) -> bool:
        az, el = pointing(h.truth().az_deg, h.truth().el_deg)
        sun = sun_altaz(lat, lon, h.wall())
        return not h.truth().is_moving and off_deg(az, sun[0]) < 3 and abs(el - sun[1]) < 3

    v.run_until(on_it, 200, "on the sun")
    return v, lat, lon


def nothing_turns_it_for(v: VirtualRotator, seconds: float) -> None:
    """No set frame for ``seconds`` (the sun moves a step in about 12 minutes)."""
    t = v.now
    v.run_for(seconds)
    assert v.frames("set", "set: clamped", since=t) == []


# An instant at which the hand comes while the session still holds the step it just reached
# (arrival not yet judged): the tracker pulled the rotor back ten seconds later, before the
# stall was judged (CI, stop 21: one run in five at test time).
HELD_STEP_WALL = 1795640009.99
# One at which the rotor is on the sun at raw -133 (a SPID's overlap): the hand takes it to
# raw 287, seventy seconds away, and only the end of that turn was ever judged.
LONG_HAND_WALL = 1795650000.0


@pytest.mark.parametrize(
    ("how", "wall"),
    [
        ("unplugged", None),
        ("silent", None),
        ("turned by hand", None),
        ("turned by hand", HELD_STEP_WALL),
        ("turned by hand", LONG_HAND_WALL),
    ],
)
def test_tracking_ends_for_good_when_the_rotor_is_out_of_the_bridges_hands(
    how: str, wall: float | None
) -> None:
    """Cold review: after an unplug (or a hand on the front panel) tracking went on; the status
    said 'tracking' while the antenna pointed elsewhere, and minutes later, once the sun had
    moved a step, the rotor turned back by itself with nobody having asked."""
    v, _lat, _lon = _tracking_the_sun(wall=wall)
    with v:
        truth = v.truth()
        if how == "unplugged":
            v.link_down()
            v.manual_rotate((truth.az_deg + 150.0) % 360.0)
            v.run_for(200.0)
            v.link_up()
        elif how == "silent":
            v.set_silent(True)
            v.run_until(lambda h: not h.session.controller.answering, 30, "the controller silent")
            v.set_silent(False)
        else:
            v.manual_rotate((truth.az_deg + 60.0) % 360.0)
        v.run_until(lambda h: h.status.available and h.status.tracking is None, 60, "ended")
        want = {
            "unplugged": {"serial link down"},
            # silent while it still held a target: no progress, so stalled may come first
            "silent": {"controller not answering", "stalled"},
            # a hand before the step's arrival was judged turns the rotor on past its target:
            # that is a controller heading elsewhere too, stopped once (motion.py rule 5)
            "turned by hand": {"turned by hand", "passed its target"},
        }
        assert v.status.tracking_ended in want[how]
        v.run_until(lambda h: not h.truth().is_moving, 120, "still")
        nothing_turns_it_for(v, 1200.0)


@pytest.mark.parametrize("name", ["off", "SUN", " moon "])
def test_a_satellite_named_off_sun_or_moon_is_called_satellite_so_and_so(name: str) -> None:
    """Review: a JSON TLE named "off" showed as R/tracking "off" while the rotor tracked it."""
    line1, line2 = synthetic_tle(
        name, SUN_EPOCH, inclination_deg=97.5, raan_deg=0.0, mean_anomaly_deg=0.0
    )
    body = Body.satellite(name, line1, line2)
    assert body.name == f"satellite {name.strip()}"
    with VirtualRotator("md01", sky=Sky(*BERLIN), wall_epoch_s=SUN_EPOCH) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(body)
        v.run_for(2.0)
        assert v.status.tracking is not None
        assert tracking_state(v.status) == f"satellite {name.strip()}"
    with pytest.raises(SkyError, match="cannot be called"):
        Body("satellite", name.strip(), (line1, line2))


def _gs232_azimuths(v: VirtualRotator) -> list[int]:
    """The azimuths of the GS-232B set frames sent (``Waaa eee``), in order."""
    return [int(w.data[1:4]) for w in v.writes if w.data.startswith(b"W")]


@pytest.mark.parametrize("start", ["before AOS", "mid-pass"])
def test_a_pass_across_the_north_takes_the_overlap_of_a_450_degree_rotor_and_never_unwinds(
    a_pass: tuple[str, str, float, float], start: str
) -> None:
    """Attack pass: a GS-232B 450 whose elevation is kept to 0..90 (no flip) waited at W010
    for a pass rising at 10 and running west through the north; at the north it unwound to
    W358 (a minute and a half of the pass pointing up to 179 degrees off) where W370 was free."""
    line1, line2, aos, los = a_pass
    if start == "before AOS":
        v, errors = fly("gs232b-450", a_pass, {"el_max_deg": 90})
    else:  # tracking starts a minute into the pass, with the rotor at 90
        speeds = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
        v = VirtualRotator(
            "gs232b-450",
            sky=Sky(*BERLIN),
            wall_epoch_s=aos + 60.0,
            emulator=speeds,
            settings={**speeds, "el_max_deg": 90},
        )
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.aim(Target(90.0, 0.0))
        v.run_until(lambda h: not h.truth().is_moving and h.truth().az_deg > 85, 60, "at 90")
        v.track(Body.satellite("TESTSAT", line1, line2))
        errors = []
        v.run_for(60.0)  # the way from 90 to the satellite, the other side of north
        while v.wall() < los:
            v.run_for(1.0)
            sat_az, sat_el = sgp4_altaz(line1, line2, *BERLIN, v.wall())
            errors.append((v.wall(), off_deg(v.truth().az_deg, sat_az), 0.0))
    with v:
        azimuths = _gs232_azimuths(v)
        tracked = azimuths[1:] if start == "mid-pass" else azimuths  # (the move to 90 first)
        assert max(t for t in tracked) > 360, tracked  # the overlap, past the north
        jumps = [abs(b - a) for a, b in zip(tracked, tracked[1:], strict=False)]
        assert max(jumps) <= 10, tracked  # never round the stop mid-pass
        assert max(e[1] for e in errors) <= 3.5, max(errors, key=lambda e: e[1])


def test_steps_finer_than_the_controllers_degree_never_send_it_what_it_already_reads(
    a_pass_clear_of_north: tuple[str, str, float, float],
) -> None:
    """Attack pass, counting the frames on the wire: with ``track_step_deg = 0.1`` a GS-232B
    (whole degrees) was sent ``W192 000`` three times over while it read 192 and 0: 132 of a
    pass's 320 set frames were the one before again (a SatEL's slews: 175 of 353)."""
    v, errors = fly("gs232b", a_pass_clear_of_north, {"track_step_deg": 0.1})
    with v:
        sets = [w.data for w in v.writes if w.data.startswith(b"W")]
        again = [a for a, b in zip(sets, sets[1:], strict=False) if a == b]
        assert len(sets) > 100 and again == [], (len(sets), again[:5])
        # and it follows as closely as before: the half degree of its rounding, and its lag
        assert max(e[1] for e in errors) <= 1.5 and max(e[2] for e in errors) <= 1.5


def test_a_rotor_ez_on_a_fine_step_is_not_sent_its_bearing_again_and_again() -> None:
    """The same, on a controller that stops to re-target: 37 AP1 frames in an hour of the sun
    where 4 bearings were new."""
    lat, lon = sun_up_somewhere(SUN_EPOCH, 20.0, 50.0)
    settings = {"track_step_deg": 0.1}
    with VirtualRotator(
        "rotorez", sky=Sky(lat, lon), wall_epoch_s=SUN_EPOCH, settings=settings
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.sun())
        v.run_for(3600.0)
        sets = [w.data for w in v.writes if w.data.startswith(b"AP1")]
        again = [a for a, b in zip(sets, sets[1:], strict=False) if a == b]
        assert len(sets) >= 3 and again == [], sets
        assert off_deg(v.truth().az_deg, sun_altaz(lat, lon, v.wall())[0]) <= 1.5


def test_a_pass_rising_in_a_keep_out_sector_is_waited_for_where_it_leaves_the_sector(
    a_pass_clear_of_north: tuple[str, str, float, float],
) -> None:
    """Attack pass: a pass rising inside a keep-out sector was not waited for at all; the rotor
    stood where it was (at 0) until the satellite left the sector, then turned 200 degrees to
    it: half a minute of the pass lost at 6 degrees a second."""
    line1, line2, aos, los = a_pass_clear_of_north
    rise_az, _ = sgp4_altaz(line1, line2, *BERLIN, aos)
    sector = [round(rise_az - 10) % 360, round(rise_az + 10) % 360]
    # (kept to 0..90 of elevation: flipped, the pass would rise clear of the sector)
    settings = {"keep_out": [sector], "el_max_deg": 90}
    v, errors = fly("rot2prog", a_pass_clear_of_north, settings)
    with v:
        exit_t = next(
            t
            for t in range(int(aos), int(los))
            if not _sector_has(sgp4_altaz(line1, line2, *BERLIN, float(t))[0], sector)
        )
        exit_az, _ = sgp4_altaz(line1, line2, *BERLIN, float(exit_t))
        waiting = [s for t, s in v.statuses if aos - 60 <= v.wall_epoch_s + t < aos]
        assert waiting and all(off_deg(s.bearing_deg or 0.0, exit_az) <= 5.0 for s in waiting), (
            exit_az,
            [s.bearing_deg for s in waiting],
        )
        after = [e[1] for e in errors if exit_t + 5 <= e[0]]
        assert after and max(after) <= 3.5, max(after)
        refusals = [e for e in v.errors("refused") if "tracking TESTSAT" in e.message]
        assert len(refusals) == 1, refusals


def _sector_has(az: float, sector: list[int]) -> bool:
    start, end = sector
    a = az % 360
    return start <= a <= end if start <= end else a >= start or a <= end


@pytest.mark.parametrize(
    ("lead_s", "back_s", "after_s"),
    [(300.0, 3600.0, 120.0), (1800.0, 300.0, 60.0)],
    ids=["an hour back", "five minutes back"],
)
def test_a_clock_stepped_back_mid_pass_sends_the_rotor_to_wait_where_the_pass_rises(
    a_pass_clear_of_north: tuple[str, str, float, float],
    lead_s: float,
    back_s: float,
    after_s: float,
) -> None:
    """Attack pass: NTP stepped the wall clock back an hour two and a half minutes into a pass;
    the pass in hand (searched from later) was kept, and the rotor stood where the satellite had
    been, waiting for that pass an hour on instead of where it rises. Its review: five minutes
    back, the pass searched for half an hour before AOS still the next one by the new clock,
    it was not searched again, and tracking, having waited for that AOS already, left the
    rotor where the satellite had been (18 degrees off the rise, 12 up) until AOS came round."""
    line1, line2, aos, _los = a_pass_clear_of_north
    speeds = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
    with VirtualRotator(
        "md01", sky=Sky(*BERLIN), wall_epoch_s=aos - lead_s, emulator=speeds, settings=speeds
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.satellite("TESTSAT", line1, line2))
        v.run_until(lambda h: h.wall() >= aos + 150.0, lead_s + 300.0, "mid-pass")
        v.wall_epoch_s -= back_s  # the clock steps back
        v.session.set_wall(v.now, v.wall())
        v.run_for(after_s)
        info = v.status.tracking
        assert info is not None and info.phase == "waiting" and info.aos_unix is not None
        assert info.aos_unix > v.wall()
        rise_az, rise_el = sgp4_altaz(line1, line2, *BERLIN, info.aos_unix)
        assert abs(rise_el) < 1.0  # (the reference agrees it rises then)
        truth = v.truth()
        assert off_deg(truth.az_deg, rise_az) <= 3.0 and truth.el_deg <= 3.0, truth


def test_a_rotor_still_on_its_way_to_the_passs_side_is_not_turned_back_by_the_next_step(
    a_pass: tuple[str, str, float, float],
) -> None:
    """Attack pass: a GS-232B 450 (it takes a new bearing while turning) at 1 degree a second,
    a fine step, tracking started a minute into a pass running west through the north, the
    rotor at 182: the first target went to the overlap (W369), the next step, a second later,
    took the side nearest where the rotor then was (W009), and at the north it unwound
    (W000 -> W359), 179 degrees off for minutes."""
    line1, line2, aos, los = a_pass
    speeds = {"az_speed_deg_s": 1.0, "el_speed_deg_s": 1.0}
    settings = {**speeds, "el_max_deg": 90, "track_step_deg": 0.1}
    v = VirtualRotator(
        "gs232b-450", sky=Sky(*BERLIN), wall_epoch_s=aos - 340.0, emulator=speeds, settings=settings
    )
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.aim(Target(182.0, 0.0))
        v.run_until(lambda h: not h.truth().is_moving and h.truth().az_deg > 180, 300, "at 182")
        v.run_until(lambda h: h.wall() >= aos + 60.0, 400, "a minute into the pass")
        sent_before = len(_gs232_azimuths(v))
        v.track(Body.satellite("TESTSAT", line1, line2))
        v.run_until(lambda h: h.wall() >= los, 900, "LOS")
        tracked = _gs232_azimuths(v)[sent_before:]
        assert tracked and tracked[0] > 360, tracked  # the pass's side: the overlap
        jumps = [abs(b - a) for a, b in zip(tracked, tracked[1:], strict=False)]
        assert max(jumps) <= 10, tracked  # never turned back, never round the stop


def _scripted_sky(passes: list[tuple[float, float, float, float]]) -> Callable[[Question], Answer]:
    """A sky worker whose satellite makes ``passes`` (AOS, LOS, azimuth at AOS, at LOS): its
    azimuth runs evenly from one to the other, its elevation up to 30 and down, and it is
    below the horizon between them. Nothing of the real sky: the geometry is the test's."""

    def at(t: float) -> tuple[float, float]:
        for aos, los, az0, az1 in passes:
            if aos <= t <= los:
                f = (t - aos) / (los - aos)
                return (az0 + f * (az1 - az0)) % 360.0, 30.0 * math.sin(math.pi * f)
        return 180.0, -20.0

    def answer(q: Question) -> Answer:
        if isinstance(q, PassQuestion):
            for aos, los, az0, az1 in passes:
                if q.utc <= los:
                    return Answer(q, Pass(aos, los, (aos + los) / 2, 30.0, az0, az1))
            return Answer(q, None)
        assert isinstance(q, PositionsQuestion)
        return Answer(q, [at(t) for t in q.times])

    return answer


def test_after_a_park_a_pass_is_waited_for_on_the_side_nearest_the_park(
    a_pass: tuple[str, str, float, float],
) -> None:
    """Review of the wait point worked out once a pass: it was worked out as the park after a
    pass set out, and of a pass that a 450-degree rotor follows as well from 10 as from 370 it
    took the side nearest where the last pass had ended (150): parked at 300, the rotor turned
    290 degrees back to W010 to wait, where W370 was 70 degrees away."""
    line1, line2, _aos, _los = a_pass  # (a satellite to name: its sky is scripted)
    t0 = SAT_EPOCH
    speeds = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
    settings = {**speeds, "el_max_deg": 90, "park_az_deg": 300, "park_el_deg": 0}
    v = VirtualRotator(
        "gs232b-450",
        sky=Sky(*BERLIN),
        wall_epoch_s=t0,
        emulator=speeds,
        settings={**settings, "track_at_los": "park"},
    )
    v.answer_sky = _scripted_sky([(t0 + 100, t0 + 400, 100, 150), (t0 + 3000, t0 + 3300, 10, 60)])
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.satellite("TESTSAT", line1, line2))
        v.run_until(lambda h: h.status.parked, 600, "parked after the first pass")
        parked = len(_gs232_azimuths(v))
        v.run_until(lambda h: h.wall() >= t0 + 3000, 3000, "the second pass rises")
        waits = _gs232_azimuths(v)[parked:]
        assert waits and waits[0] == 370, waits  # from the park at 300, not where it ended


def test_a_hy_gain_rotor_is_at_a_pass_across_its_stop_when_it_rises(
    a_pass: tuple[str, str, float, float],
) -> None:
    """Rule 2, on a Hy-Gain rotor (stop at south, emulator rule 12): the last pass ended at 170,
    the next rises at 190. Those are 20 degrees apart on the scale and 340 along the rotor's
    travel (motion.py rule 5). A review: the wait was timed by the scale, about 28 s for about
    60 s of turning, and the rotor came to the pass some 35 s after it rose."""
    line1, line2, _aos, _los = a_pass  # (a satellite to name: its sky is scripted)
    t0 = SAT_EPOCH
    emulator = {"start_az_deg": 100.0, "stop_at_south": True}
    v = VirtualRotator("rotorez", sky=Sky(*BERLIN), wall_epoch_s=t0, emulator=emulator)
    aos = t0 + 3000
    v.answer_sky = _scripted_sky([(t0 + 100, t0 + 400, 100, 170), (aos, aos + 300, 190, 250)])
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.satellite("TESTSAT", line1, line2))
        v.run_until(lambda h: h.wall() >= t0 + 500, 600, "the first pass over")
        assert off_deg(v.truth().az_deg, 170.0) <= 4.0  # it stayed where that pass ended
        v.run_until(lambda h: h.wall() >= aos, 3000, "the second pass rises")
        assert off_deg(v.truth().az_deg, 190.0) <= 4.0, v.truth()
        assert not v.truth().is_moving
        assert v.errors() == []


def _iss_elements(t0: float) -> tuple[tuple[str, str], tuple[str, str]]:
    """Rule 10's tests: the ISS's elements a week old and of the day (another plane)."""
    old = synthetic_tle("", t0 - 7 * 86400, inclination_deg=51.6, raan_deg=0, mean_anomaly_deg=0)
    new = synthetic_tle("", t0, inclination_deg=51.6, raan_deg=40, mean_anomaly_deg=0)
    return old, new


def _write_tle(path: Path, tle: tuple[str, str], mtime_s: float) -> None:
    """The file as cron writes it, its modification time set (the catalog sees a change by it,
    never by how fast the test ran)."""
    path.write_text(f"ISS (ZARYA)\n{tle[0]}\n{tle[1]}\n")
    os.utime(path, ns=(int(mtime_s * 1e9),) * 2)


def _by_elements(by: dict[tuple[str, str], Callable[[Question], Answer]]) -> Callable[..., Answer]:
    """The sky worker: the file read as it reads it, each body's passes scripted by elements."""

    def sky(q: Question) -> Answer:
        if isinstance(q, LookupQuestion):
            return answer(q)
        assert q.body.tle is not None
        return by[q.body.tle](q)

    return sky


def _tracking_by_name(v: VirtualRotator, path: Path) -> None:
    """The controller answers, then the ISS is tracked by its name in ``path``."""
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.mailbox.put_track(Track(None, Source.MQTT, LookupQuestion(TleCatalog(path), "iss (zarya)")))
    v._take()


def _md01_in_berlin(t0: float) -> VirtualRotator:
    speeds = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
    return VirtualRotator(
        "md01", sky=Sky(*BERLIN), wall_epoch_s=t0, emulator=speeds, settings=speeds
    )


def test_a_satellite_tracked_by_name_takes_the_tle_files_new_elements_after_a_pass(
    tmp_path: Path,
) -> None:
    """An attack pass: ISS tracked by name for days, the TLE file refreshed by cron every
    morning: the bridge flew every pass by the elements of the day tracking started, however
    stale (a reboost moves the passes by minutes), though the file was read again for any new
    look-up. The sky is scripted by elements: the old ones' next pass rises at 200 in 80
    minutes, the new ones' at 10 in 45."""
    t0 = SAT_EPOCH
    old, new = _iss_elements(t0)
    path = tmp_path / "amateur.tle"
    _write_tle(path, old, t0 - 86400)
    v = _md01_in_berlin(t0)
    v.answer_sky = _by_elements(
        {
            old: _scripted_sky([(t0 + 100, t0 + 400, 100, 150), (t0 + 4800, t0 + 5100, 200, 250)]),
            new: _scripted_sky([(t0 + 2700, t0 + 3000, 10, 60)]),
        }
    )
    with v:
        _tracking_by_name(v, path)
        v.run_until(lambda h: h.wall() >= t0 + 200, 300, "the first pass is under way")
        _write_tle(path, new, t0)  # cron, mid-pass
        v.run_until(lambda h: h.wall() >= t0 + 2690, 3000, "just before the new elements' AOS")
        info = v.status.tracking
        assert info is not None and info.aos_unix == pytest.approx(t0 + 2700, abs=1), info
        assert v.status.state is MotionState.IDLE
        assert off_deg(v.truth().az_deg, 10.0) <= 2.0, v.truth()  # waiting where it rises


@pytest.mark.parametrize(
    ("days_after_clock", "said"),
    [
        (-123.0, "by elements 123 days old"),
        (-2.0, None),
        (40.0, "by elements dated 40 days after this station's clock"),
        (1.0, None),
    ],
)
def test_elements_months_old_or_dated_after_the_clock_are_said_when_tracking_starts(
    days_after_clock: float, said: str | None, caplog: pytest.LogCaptureFixture
) -> None:
    """An attack pass: elements four months old (a cron job that stopped) were tracked
    without a word, their passes minutes off; so were elements dated weeks after the
    station's clock (a Raspberry Pi without a real-time clock, started before its time was
    set), every position for the wrong time. The log says it once, and so does the status's
    tracking block, where a page shows the pass (rule 11); elements two days old, or a day
    ahead (an operator's predicted ones), are not flagged."""
    t0 = SAT_EPOCH
    epoch = t0 + days_after_clock * 86400
    line1, line2 = synthetic_tle("", epoch, inclination_deg=51.6, raan_deg=0, mean_anomaly_deg=0)
    v = VirtualRotator("md01", sky=Sky(*BERLIN), wall_epoch_s=t0)
    v.answer_sky = _scripted_sky([(t0 + 100, t0 + 400, 100, 150)])
    with v, caplog.at_level("WARNING", logger="bridge.session.tracking"):
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.satellite("AO-7", line1, line2))
        v.run_for(30.0)
        warned = [r.getMessage() for r in caplog.records if "AO-7 by elements" in r.getMessage()]
        if said is not None:
            assert len(warned) == 1 and f"AO-7 {said}" in warned[0], warned
            day = datetime.fromtimestamp(epoch, UTC).strftime("%Y-%m-%d")
            assert f"(epoch {day} " in warned[0], warned
        else:
            assert warned == []
        info = v.status.tracking
        assert info is not None, v.status
        assert info.elements_stale is (said is not None and days_after_clock < 0), info
        assert info.elements_ahead is (said is not None and days_after_clock > 0), info
        assert info.elements_epoch_unix == pytest.approx(epoch, abs=0.01)
        assert tracking_state(v.status) != "off"


def test_elements_that_age_past_stale_while_tracked_are_shown_stale() -> None:
    """Rule 11: the status judges the elements' age at each refresh, not once at the start:
    a file that stops being refreshed shows it on the page while the rotator tracks on."""
    t0 = SAT_EPOCH
    line1, line2 = synthetic_tle(
        "", t0 - STALE_DAYS * 86400 + 60, inclination_deg=51.6, raan_deg=0, mean_anomaly_deg=0
    )
    v = VirtualRotator("md01", sky=Sky(*BERLIN), wall_epoch_s=t0)
    v.answer_sky = _scripted_sky([(t0 + 100, t0 + 400, 100, 150)])
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.track(Body.satellite("AO-7", line1, line2))
        v.run_until(
            lambda h: h.status.tracking is not None and h.status.tracking.azimuth_deg is not None,
            30,
            "shown",
        )
        assert v.status.tracking is not None and not v.status.tracking.elements_stale
        v.run_until(
            lambda h: h.status.tracking is not None and h.status.tracking.elements_stale,
            120,
            "a minute on, older than STALE_DAYS",
        )
        assert v.wall() >= t0 + 60


def test_new_elements_read_while_a_pass_is_under_way_wait_for_its_end(tmp_path: Path) -> None:
    """Rule 10: the file looked at between two passes 20 s apart, its answer 30 s late (the
    sky worker busy): the second pass, under way by then, is flown to its end by the elements
    it began with; the new ones take over from the pass after it."""
    t0 = SAT_EPOCH
    old, new = _iss_elements(t0)
    path = tmp_path / "amateur.tle"
    _write_tle(path, old, t0 - 86400)
    passes = [(t0 + 100, t0 + 400, 100, 150), (t0 + 420, t0 + 720, 150, 200)]
    scripted = _by_elements(
        {
            old: _scripted_sky([*passes, (t0 + 4800, t0 + 5100, 200, 250)]),
            new: _scripted_sky([(t0 + 2700, t0 + 3000, 10, 60)]),
        }
    )
    lookups: list[float] = []

    def sky(q: Question) -> Answer:
        """The sky worker answers in order: what is asked after a slow look-up waits for it."""
        slow = isinstance(q, LookupQuestion) and v.wall() > t0 + 400  # (the one after LOS)
        queued = max((due for due, _g, _a in v._answers), default=v.now)
        v.sky_delay_s = max(queued, v.now + (30.0 if slow else 0.0)) - v.now  # (read after)
        if isinstance(q, LookupQuestion):
            lookups.append(v.wall())
        return scripted(q)

    v = _md01_in_berlin(t0)
    v.answer_sky = sky
    with v:
        _tracking_by_name(v, path)
        v.run_until(lambda h: h.wall() >= t0 + 200, 300, "the first pass is under way")
        _write_tle(path, new, t0)
        v.run_until(lambda h: h.wall() >= t0 + 440, 300, "the second pass under way")
        assert [t for t in lookups if t0 + 400 < t < t0 + 420], lookups  # answered at 430 or so
        worst = 0.0
        while v.wall() < t0 + 715:
            v.run_for(5.0)
            body_az = 150.0 + 50.0 * (v.wall() - (t0 + 420)) / 300.0
            worst = max(worst, off_deg(v.truth().az_deg, body_az))
        assert worst <= 5.0, worst  # followed to its end by the old elements
        v.run_until(lambda h: h.wall() >= t0 + 2690, 3000, "just before the new elements' AOS")
        info = v.status.tracking
        assert info is not None and info.aos_unix == pytest.approx(t0 + 2700, abs=1), info
        assert off_deg(v.truth().az_deg, 10.0) <= 2.0, v.truth()


def test_new_elements_written_while_the_rotor_waits_for_a_pass_are_taken_before_it(
    tmp_path: Path,
) -> None:
    """Rule 10: tracking started hours before the pass, cron's file lands meanwhile: the pass
    is waited for where the new elements say it rises, not where the old ones did."""
    t0 = SAT_EPOCH
    old, new = _iss_elements(t0)
    path = tmp_path / "amateur.tle"
    _write_tle(path, old, t0 - 86400)
    v = _md01_in_berlin(t0)
    v.answer_sky = _by_elements(
        {
            old: _scripted_sky([(t0 + 3000, t0 + 3300, 200, 250)]),
            new: _scripted_sky([(t0 + 2700, t0 + 3000, 10, 60)]),
        }
    )
    with v:
        _tracking_by_name(v, path)
        v.run_until(
            lambda h: (
                h.status.state is MotionState.IDLE and off_deg(h.truth().az_deg, 200.0) <= 1.0
            ),
            120,
            "waiting where the old elements' pass rises",
        )
        v.run_until(lambda h: h.wall() >= t0 + 600, 700, "a while later")
        _write_tle(path, new, t0)
        v.run_until(lambda h: h.wall() >= t0 + 2690, 3000, "just before the new elements' AOS")
        assert v.status.state is MotionState.IDLE
        assert off_deg(v.truth().az_deg, 10.0) <= 2.0, v.truth()
