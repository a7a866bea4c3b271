"""Tracking end to end: ``R/track`` through a private mosquitto, the SPID emulator (an MD-01) on
a pty through pyserial, the App in-process and its rotctld port. The virtual-time tests
(tests/engine/test_session_tracking.py) prove the pass logic over hours of sky; these prove
the wiring a user touches: the topics, the retained ``R/tracking``, the status's ``tracking``
block, the refusals on ``R/error``, the TLE file and Home Assistant's track select.

What is asserted is what a user sees: where the rotor really is (the emulator's ground truth),
the retained payloads and the error messages. Positions are judged against references written
in the tests (tests/support/sky.py: the Almanac's low-precision sun, sgp4 with our own frame
rotations), never against the library the bridge uses.

The bridge runs on a wall clock of the test's own (``Wall``: a fixed instant when the test
starts, going on at the real rate), and the references are asked at that clock's times: the
sky is the same at any time of day the suite runs.
"""

from __future__ import annotations

import json
import time
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np

from bridge.app import App
from bridge.settings.pointing import StationSettings, TrackingSettings
from tests.engine.test_session_tracking import (
    BERLIN,
    SAT_EPOCH,
    SUN_EPOCH,
    off_deg,
    pointing,
    sun_up_somewhere,
)
from tests.integration.test_rotctld_integration import ask, connect
from tests.support import free_port
from tests.support.mqtt import Message, retained_snapshot
from tests.support.rig import FAST_POLLING, Rig
from tests.support.sky import sgp4_altaz, sgp4_altaz_array, sun_altaz, synthetic_tle, tle_with_pass
from tests.support.waiting import wait_until

# a quick MD-01 (115200 baud, re-targets while turning): a turn to the sun takes a second or
# two, a flipped one (elevation past 90) too. The bridge is told the same speeds, and settles
# sooner than the rig's SPID default (nothing here needs the slow 600-baud Rot2Prog's margin).
QUICK_EMU = {"az_speed_deg_s": 120.0, "el_speed_deg_s": 120.0}
QUICK_BRIDGE = {"az_speed_deg_s": 120.0, "el_speed_deg_s": 120.0, "settle_s": 0.3}
ISS_NAME = "ISS (ZARYA)"


class Wall:
    """A wall clock that reads ``epoch`` when made and goes on at the real rate."""

    def __init__(self, epoch: float) -> None:
        self.epoch, self._t0 = epoch, time.monotonic()

    def __call__(self) -> float:
        return self.epoch + time.monotonic() - self._t0


SUN_STATION = sun_up_somewhere(SUN_EPOCH)


def start(
    rig: Rig,
    station: tuple[float, float] | None,
    tle_file: Path | None = None,
    wall: Wall | None = None,
) -> App:
    """The App on the rig's settings with ``[station]`` and ``[tracking] tle_file`` (the Rig
    has neither), every rotator ready (online and settled), on ``wall`` (a new one at
    SUN_EPOCH by default)."""
    update: dict[str, Any] = {"tracking": TrackingSettings(tle_file=tle_file)}
    if station is not None:
        update["station"] = StationSettings(latitude_deg=station[0], longitude_deg=station[1])
    rig.app = App(rig.settings.model_copy(update=update), wall=wall or Wall(SUN_EPOCH))
    rig.app.start()
    for r in rig.rotators:
        rig.ready(r["id"])
    return rig.app


def doc(m: Message) -> dict[str, Any]:
    return json.loads(m.payload)


def status_after(rig: Rig, rid: str, t: float, want: Any) -> dict[str, Any]:
    """The first status published after ``t`` for which ``want(status)`` holds."""
    return doc(rig.probe.wait_for(rig.topic(rid, "status"), lambda m: want(doc(m)), after=t))


def error_after(rig: Rig, rid: str, t: float) -> dict[str, Any]:
    return doc(rig.probe.wait_for(rig.topic(rid, "error"), after=t))


def on_the_sun(station: tuple[float, float], wall: Wall) -> Any:
    """A predicate on the emulator's state: at rest within 2 deg of the sun on both axes."""

    def there(s: Any) -> bool:
        sun_az, sun_el = sun_altaz(*station, wall())
        az, el = pointing(s.az_deg, s.el_deg)
        return not s.is_moving and off_deg(az, sun_az) <= 2.0 and abs(el - sun_el) <= 2.0

    return there


def sunrise_and_sunset(station: tuple[float, float], t: float) -> tuple[float, float]:
    """The reference's elevation-0 crossings around ``t`` (the sun is up at t), to 1 s."""

    def crossing(up: float, down: float) -> float:
        while abs(down - up) > 1.0:
            mid = (up + down) / 2
            if sun_altaz(*station, mid)[1] > 0:
                up = mid
            else:
                down = mid
        return (up + down) / 2

    rise = t
    while sun_altaz(*station, rise)[1] > 0:
        rise -= 600.0
    sets = t
    while sun_altaz(*station, sets)[1] > 0:
        sets += 600.0
    return crossing(t, rise), crossing(t, sets)


def unix(iso: str) -> float:
    return datetime.fromisoformat(iso).timestamp()


# -- the sun on an MD-01, and every way tracking ends -------------------------------------------
def test_track_sun_turns_an_md01_to_the_sun_and_the_status_says_so(rig: Rig) -> None:
    station, wall = SUN_STATION, Wall(SUN_EPOCH)
    emu = rig.add("dish", model="md01", emu={**QUICK_EMU, "start_az_deg": 0}, **QUICK_BRIDGE)
    start(rig, station, wall=wall)
    snap = rig.retained()
    assert snap["rotor/tracking"] == b"off"  # a rotator that can track says so from the start
    assert "tracking" not in json.loads(snap["rotor/status"])

    t = time.monotonic()
    rig.probe.publish("rotor/track", "sun")
    rig.probe.wait_value("rotor/tracking", "sun", after=t)
    truth = emu.wait_for(on_the_sun(station, wall), 15)  # at rest within 2 deg of the reference
    assert emu.frames("set: clamped") == []  # never sent past a stop

    status = status_after(
        rig, "dish", t, lambda s: s.get("tracking", {}).get("phase") == "tracking"
    )
    block = status["tracking"]
    at = unix(status["time"])  # the block is at most INFO_EVERY_S (5 s) older than the status
    sun_az, sun_el = sun_altaz(*station, at)
    assert block["body"] == "sun"
    assert block["flip"] == (truth.el_deg > 90.0), (block, truth)  # flown flipped, and says so
    assert off_deg(block["azimuth"], sun_az) <= 0.5 and abs(block["elevation"] - sun_el) <= 0.5
    next_az, next_el = sun_altaz(*station, at + 60.0)  # "next": the body in a minute
    assert off_deg(block["next"]["azimuth"], next_az) <= 0.5, block
    assert abs(block["next"]["elevation"] - next_el) <= 0.5, block
    # the pass in progress: today's sunrise and sunset (elevation 0, no refraction)
    rise, sets = sunrise_and_sunset(station, at)
    assert abs(unix(block["aos"]) - rise) <= 30.0 and abs(unix(block["los"]) - sets) <= 30.0
    assert off_deg(block["aos_azimuth"], sun_altaz(*station, rise)[0]) <= 0.5, block
    assert "tracking_ended" not in status
    assert rig.retained()["rotor/tracking"] == b"sun"


def test_off_stop_lock_a_manual_target_and_a_rotctld_p_each_end_tracking(rig: Rig) -> None:
    station, wall = SUN_STATION, Wall(SUN_EPOCH)
    port = free_port()
    emu = rig.add("dish", model="md01", emu=QUICK_EMU, rotctld_port=port, **QUICK_BRIDGE)
    start(rig, station, wall=wall)

    def track_sun() -> None:
        t = time.monotonic()
        rig.probe.publish("rotor/track", "sun")
        rig.probe.wait_value("rotor/tracking", "sun", after=t)

    def ended(t: float, why: str) -> dict[str, Any]:
        """Tracking is over, for ``why``: R/tracking (retained) is off, the status says why."""
        rig.probe.wait_value("rotor/tracking", "off", after=t)
        status = status_after(rig, "dish", t, lambda s: s.get("tracking_ended") == why)
        assert "tracking" not in status, status
        snap = rig.retained()
        assert snap["rotor/tracking"] == b"off"
        assert json.loads(snap["rotor/status"])["tracking_ended"] == why
        return status

    track_sun()
    t = time.monotonic()
    rig.probe.publish("rotor/track", "OFF")  # any case
    ended(t, "off")

    track_sun()
    t = time.monotonic()
    rig.probe.publish("rotor/stop", "STOP")
    ended(t, "stop")

    track_sun()
    t = time.monotonic()
    rig.probe.publish("rotor/lock", "ON")
    ended(t, "lock")
    # shown ON once saved (kept.py rule 2): a lock OFF before that save shows no change at all
    rig.probe.wait_value("rotor/lock/state", "ON", after=t)
    # locked: tracking is refused like any motion, and nothing starts
    t = time.monotonic()
    rig.probe.publish("rotor/track", "sun")
    err = error_after(rig, "dish", t)
    assert err["kind"] == "refused" and err["command"] == "track 'sun'", err
    assert "locked" in err["message"], err
    assert rig.retained()["rotor/tracking"] == b"off"
    t = time.monotonic()
    rig.probe.publish("rotor/lock", "OFF")
    rig.probe.wait_value("rotor/lock/state", "OFF", after=t)

    track_sun()
    emu.wait_for(on_the_sun(station, wall), 15)
    t = time.monotonic()
    rig.probe.publish("rotor/target", "10 10")
    ended(t, "mqtt target")
    # the manual target is taken, and kept: tracking does not come back for the rotor
    emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 10) <= 0.5, 10)
    assert abs(emu.state().el_deg - 10) <= 0.5
    status_after(
        rig, "dish", t, lambda s: (s["state"], s["bearing"], s["elevation"]) == ("idle", 10, 10)
    )

    track_sun()
    with connect(port) as sock:
        t = time.monotonic()
        ask(sock, b"P 100.00 20.00\n", b"RPRT 0\n")  # Gpredict takes over
    ended(t, "rotctld target")
    emu.wait_for(
        lambda s: not s.is_moving and abs(s.az_deg - 100) <= 0.5 and abs(s.el_deg - 20) <= 0.5, 10
    )


def test_a_retained_track_is_refused_and_never_followed(rig: Rig) -> None:
    station = SUN_STATION
    emu = rig.add("dish", model="md01", emu={**QUICK_EMU, "start_az_deg": 0}, **QUICK_BRIDGE)
    # left retained on the broker (a dashboard button set to retain): every restart of the
    # bridge or the broker would start tracking again, turning the rotor unasked
    rig.probe.publish("rotor/track", "sun", retain=True)
    t = time.monotonic()
    start(rig, station)
    err = error_after(rig, "dish", t)
    assert err["kind"] == "refused" and "retained" in err["message"], err
    assert err["command"] == "track 'sun'", err
    snap = rig.retained()
    assert snap["rotor/tracking"] == b"off"
    assert "tracking" not in json.loads(snap["rotor/status"])
    assert emu.frames("set", "set: clamped") == []  # the rotor was never sent anywhere
    # the same command sent live is followed: it was the retain flag that was refused
    rig.probe.publish("rotor/track", "", retain=True)  # cleared, as the refusal says
    t = time.monotonic()
    rig.probe.publish("rotor/track", "sun")
    rig.probe.wait_value("rotor/tracking", "sun", after=t)


# -- satellites: the TLE file, JSON elements ----------------------------------------------------
def a_pass_ahead(now: float, lead_s: float = 60.0) -> tuple[str, str, float, float]:
    """A synthetic satellite (epoch: now) whose first pass over Berlin rises at least lead_s
    from now, and that is not up before it: the bridge starts out waiting for that pass."""
    for k in range(20):
        line1, line2, aos, los = tle_with_pass(*BERLIN, now + lead_s + 300.0 * k)
        before = np.arange(now, aos - 1.0, 5.0)
        _, el = sgp4_altaz_array(line1, line2, *BERLIN, before)
        if (el < 0).all():
            return line1, line2, aos, los
    raise AssertionError("no synthetic pass clear of another in 100 minutes")


def test_satellites_by_name_from_the_tle_file_which_is_read_again_when_it_changes(
    rig: Rig, tmp_path: Path
) -> None:
    wall = Wall(SAT_EPOCH)
    line1, line2, aos, los = a_pass_ahead(wall())
    tle_file = tmp_path / "active.txt"
    tle_file.write_text(f"{ISS_NAME}\n{line1}\n{line2}\n")
    emu = rig.add("dish", model="md01", emu=QUICK_EMU, **QUICK_BRIDGE)
    start(rig, BERLIN, tle_file, wall=wall)
    # Home Assistant's track select offers the file's satellites
    ha = retained_snapshot(rig.broker.port, "homeassistant/#")
    select = json.loads(ha["homeassistant/select/rotorbridge_rotor_r_dish/track/config"])
    assert select["options"] == ["off", "sun", "moon", ISS_NAME]
    assert select["command_topic"] == "rotor/track"

    t = time.monotonic()
    rig.probe.publish("rotor/track", "  iss (zarya) ")  # by name, ignoring case and blanks
    rig.probe.wait_value("rotor/tracking", ISS_NAME, after=t)
    status = status_after(rig, "dish", t, lambda s: s.get("tracking", {}).get("aos") is not None)
    block = status["tracking"]
    assert (block["body"], block["phase"]) == (ISS_NAME, "waiting"), block
    assert abs(unix(block["aos"]) - aos) <= 2.0 and abs(unix(block["los"]) - los) <= 2.0, block
    aos_az, _ = sgp4_altaz(line1, line2, *BERLIN, aos)
    assert off_deg(block["aos_azimuth"], aos_az) <= 1.0, (block, aos_az)
    during = np.arange(aos, los, 1.0)
    max_el = float(sgp4_altaz_array(line1, line2, *BERLIN, during)[1].max())
    assert abs(block["max_elevation"] - max_el) <= 0.5, (block, max_el)
    # the pass's predicted track, for a sky plot: from where it rises to where it sets
    track = status_after(rig, "dish", t, lambda s: "pass_track" in s.get("tracking", {}))
    points = track["tracking"]["pass_track"]
    los_az, _ = sgp4_altaz(line1, line2, *BERLIN, los)
    assert 2 <= len(points) <= 40, points
    assert off_deg(points[0][0], aos_az) <= 1.0 and off_deg(points[-1][0], los_az) <= 1.0
    assert abs(max(el for _az, el in points) - max_el) <= 2.0, (points, max_el)
    # waiting where the pass rises, at the minimum elevation (0), before AOS
    emu.wait_for(
        lambda s: (
            not s.is_moving
            and off_deg(pointing(s.az_deg, s.el_deg)[0], aos_az) <= 2.0
            and abs(pointing(s.az_deg, s.el_deg)[1]) <= 1.0
        ),
        15,
    )
    assert wall() < aos, "the rotor got to the AOS azimuth only after AOS"

    # an unknown name: refused, naming the file (and nothing changes)
    t = time.monotonic()
    rig.probe.publish("rotor/track", "HUBBLE")
    err = error_after(rig, "dish", t)
    assert err["kind"] == "refused" and err["command"] == "track 'HUBBLE'", err
    assert "'HUBBLE'" in err["message"] and str(tle_file) in err["message"], err
    assert rig.retained()["rotor/tracking"] == ISS_NAME.encode()

    # cron refreshes the file with one more satellite: taken by name without a restart
    noaa1, noaa2 = synthetic_tle(
        "NOAA 19", wall(), inclination_deg=99.0, raan_deg=40.0, mean_anomaly_deg=0.0,
        catalog=33591,
    )  # fmt: skip
    tle_file.write_text(f"{ISS_NAME}\n{line1}\n{line2}\nNOAA 19\n{noaa1}\n{noaa2}\n")
    t = time.monotonic()
    rig.probe.publish("rotor/track", "noaa 19")
    rig.probe.wait_value("rotor/tracking", "NOAA 19", after=t)
    status = status_after(rig, "dish", t, lambda s: s.get("tracking", {}).get("body") == "NOAA 19")
    assert "tracking_ended" not in status  # one body after another: nothing ended

    # the elements themselves, as JSON: no file needed
    test1, test2 = synthetic_tle(
        "TESTSAT", wall(), inclination_deg=97.5, raan_deg=200.0, mean_anomaly_deg=90.0,
        catalog=99998,
    )  # fmt: skip
    t = time.monotonic()
    rig.probe.publish("rotor/track", json.dumps({"tle": ["TESTSAT", test1, test2]}))
    rig.probe.wait_value("rotor/tracking", "TESTSAT", after=t)

    def testsat_placed(s: dict[str, Any]) -> bool:
        block = s.get("tracking", {})
        return block.get("body") == "TESTSAT" and block.get("elevation") is not None

    status = status_after(rig, "dish", t, testsat_placed)
    block = status["tracking"]
    # the block is at most INFO_EVERY_S older than its status: a LEO's elevation moves less
    # than 0.1 deg/s seen from the ground (most of its orbit is below the horizon)
    _, ref_el = sgp4_altaz(test1, test2, *BERLIN, unix(status["time"]))
    assert abs(block["elevation"] - ref_el) <= 1.0, (block, ref_el)


# -- who cannot track ---------------------------------------------------------------------------
def test_a_dcu1_cannot_track(rig: Rig) -> None:
    rig.add("dish", model="md01", emu=QUICK_EMU, **QUICK_BRIDGE)
    rig.add("wire", model="dcu1")
    start(rig, SUN_STATION)
    snap = rig.retained()
    assert snap["rotor/dish/tracking"] == b"off"
    assert "rotor/wire/tracking" not in snap  # nothing offered that it cannot do
    ha = retained_snapshot(rig.broker.port, "homeassistant/#")
    assert "homeassistant/select/rotorbridge_rotor_r_dish/track/config" in ha
    assert not [topic for topic in ha if "_r_wire/track" in topic]
    t = time.monotonic()
    rig.probe.publish("rotor/wire/track", "sun")
    err = error_after(rig, "wire", t)
    assert err["kind"] == "refused" and err["command"] == "track 'sun'", err
    assert "cannot report where it points" in err["message"], err


def test_without_a_station_tracking_is_refused_naming_the_station(rig: Rig) -> None:
    emu = rig.add("dish", model="md01", emu=QUICK_EMU, **QUICK_BRIDGE)
    start(rig, None)
    assert "rotor/tracking" not in rig.retained()
    ha = retained_snapshot(rig.broker.port, "homeassistant/#")
    assert "homeassistant/sensor/rotorbridge_rotor_r_dish/bearing/config" in ha
    assert not [topic for topic in ha if "/track" in topic or "next_aos" in topic]
    t = time.monotonic()
    rig.probe.publish("rotor/track", "sun")
    err = error_after(rig, "dish", t)
    assert err["kind"] == "refused" and "[station]" in err["message"], err
    assert emu.frames("set", "set: clamped") == []


def test_a_station_taken_out_leaves_no_retained_tracking_behind(rig: Rig) -> None:
    """A rotator that could track and follow WSJT-X left ``R/tracking`` and ``R/follow/state``
    retained; started again without ``[station]`` it can do neither, publishes neither, and
    they stayed for ever: the Node-RED page, which offers Sun, Moon and a satellite once
    ``R/tracking`` arrives (docs/node-red.md), offered what the bridge then refused
    (interfaces/mqtt/stale.py rule 5). Deleted at the next start's first look."""
    rig.add("dish", model="md01", emu=QUICK_EMU, **QUICK_BRIDGE)
    rig.sections = {"wsjtx": {"enabled": True, "port": free_port()}}
    start(rig, SUN_STATION)
    before = rig.retained()
    assert (before["rotor/tracking"], before["rotor/follow/state"]) == (b"off", b"off")
    rig.stop()
    start(rig, None)
    wait_until(
        lambda: not {"rotor/tracking", "rotor/follow/state"} & set(rig.retained()),
        timeout_s=10,
        what="the tracking and following states deleted",
    )
    assert json.loads(rig.retained()["rotor/info"])["can_track"] is False
    t = time.monotonic()
    rig.probe.publish("rotor/track", "sun")
    assert "[station]" in error_after(rig, "dish", t)["message"]


def test_a_tle_with_a_digit_that_is_not_ascii_is_refused_and_tracking_still_works(
    rig: Rig,
) -> None:
    """An attack pass: a TLE sent on ``R/track`` with a superscript two (``²``, which
    ``str.isdigit`` takes and ``int`` refuses) in its lines was said nowhere: the check of its
    checksum raised ValueError on paho's thread, the log had a traceback, ``R/error`` nothing.
    It is refused there, naming the line, nothing moves, and the sun is tracked after it."""
    emu = rig.add("dish", model="md01", emu=QUICK_EMU, **QUICK_BRIDGE)
    wall = Wall(SUN_EPOCH)
    start(rig, SUN_STATION, wall=wall)
    line1, line2 = synthetic_tle(
        "X", SUN_EPOCH, inclination_deg=51.6, raan_deg=0.0, mean_anomaly_deg=0.0
    )
    for bad in ([line1[:68] + "²", line2], [line1[:30] + "²" + line1[31:], line2]):
        t = time.monotonic()
        rig.probe.publish("rotor/track", json.dumps({"tle": ["X", *bad]}))
        err = error_after(rig, "dish", t)
        assert err["kind"] == "refused" and "TLE line 1" in err["message"], err
        assert "ASCII" in err["message"], err
    assert emu.frames("set", "set: clamped") == []
    rig.probe.publish("rotor/track", "sun")
    emu.wait_for(on_the_sun(SUN_STATION, wall), timeout_s=20)


def test_an_elevation_box_tracks_as_the_elevation_of_two_boxes(rig: Rig) -> None:
    """session/feature_commands.py rule 6 refuses tracking on a Prosistel D on an elevation
    rotor configured on its own (its bearing is the elevation: attack 19); as the elevation box
    of an az/el rotator of two boxes it is sent the sun's elevation, the azimuth box the
    sun's azimuth."""
    wall = Wall(SUN_EPOCH)
    az = rig.open_line(rig, "dish-az", "md01", {**QUICK_EMU, "start_az_deg": 0.0})
    el = rig.open_line(rig, "dish-el", "prosistel-el", {"start_el_deg": 10.0})
    rig.rotators.append(
        {
            "id": "dish",
            "azimuth": {"model": "md01", "port": str(az.path)},
            "elevation": {"model": "prosistel-el", "port": str(el.path)},
            **FAST_POLLING,
        }
    )
    station = StationSettings(latitude_deg=SUN_STATION[0], longitude_deg=SUN_STATION[1])
    rig.app = App(rig.settings.model_copy(update={"station": station}), wall=wall)
    rig.app.start()
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)
    t = time.monotonic()
    rig.probe.publish("rotor/track", "sun")
    rig.probe.wait_value("rotor/tracking", "sun", after=t)

    def on_the_sun() -> bool:
        """Both boxes at rest, within 2 degrees of the sun each on its own axis."""
        sun_az, sun_el = sun_altaz(*SUN_STATION, wall())
        a, e = az.emu.state(), el.emu.state()
        if a.is_moving or e.is_moving or e.el_deg is None:
            return False
        return off_deg(a.az_deg, sun_az) <= 2.0 and abs(e.el_deg - sun_el) <= 2.0

    wait_until(on_the_sun, timeout_s=30, what="both boxes on the sun")
