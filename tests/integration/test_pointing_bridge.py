"""Pointing end to end: an offset scale, presets, park, keep-out, locator targets and auto-park,
through the real wiring (a private mosquitto, the Rotor-EZ emulator on a pty through pyserial,
the App in-process, its rotctld port).

What is asserted is what a user sees: the frames the controller received (the emulator's log:
``AP1xxx<CR>`` is the Rotor-EZ's "store and go"), where the rotor really is (its ground truth),
the retained payloads and the rotctld replies. The great-circle reference is computed here, from
the Maidenhead definition and vector geometry, never by bridge.core.geo.
"""

from __future__ import annotations

import json
import math
import time
from typing import Any

from bridge.app import App
from bridge.emulators.base import LoggedFrame, MotionEvent
from bridge.emulators.pty import EmulatedPort
from bridge.settings.pointing import StationSettings
from tests.integration.test_rotctld_integration import ask, connect
from tests.support import free_port
from tests.support.rig import Rig

# A south-centred scale: true bearing = controller bearing + 180
SOUTH: dict[str, Any] = {
    "az_offset_deg": 180,
    "presets": {"JA": 330, "EU": 45},
    "park_az_deg": 0,
    "keep_out": [[200, 220]],
}
# a quick rotor with a short brake for the moves that only need to arrive (the bridge waits at
# least as long as the controller's brake delay, as on real hardware)
QUICK_EMU = {"speed_deg_s": 120.0, "brake_delay_s": 0.5, "jitter_deg": 0}
QUICK_BRIDGE = {"brake_delay_s": 0.5, "settle_s": 0.3}
# auto-park: the shortest quiet spell the settings allow; the rotor at the rig's 40 deg/s, so
# that a park and a hand on the front panel take long enough to be caught turning
PARKING = {"park_az_deg": 0, "park_after_idle_s": 5, **QUICK_BRIDGE}
PARKING_EMU = {"brake_delay_s": 0.5, "jitter_deg": 0}
PARK_FRAME = b"AP1000\r"
EARTH_RADIUS_KM = 6371.0


def start(rig: Rig, station_locator: str | None = None) -> App:
    """The App on the rig's settings, with ``[station] locator`` if given (Rig has none)."""
    settings = rig.settings
    if station_locator is not None:
        station = StationSettings(locator=station_locator)
        settings = settings.model_copy(update={"station": station})
    rig.app = App(settings)
    rig.app.start()
    rig.ready("tower")
    return rig.app


def motion_frames(emu: EmulatedPort[Any], since: float = -math.inf) -> list[LoggedFrame]:
    """What moved or stopped the rotor (bearings, go, stop) since ``since``, whatever came of it."""
    return [
        f
        for f in emu.log()
        if f.time_s >= since and (f.data.startswith((b"AP", b"AM")) or f.data == b";")
    ]


def events(emu: EmulatedPort[Any], since: float, *kinds: str) -> list[MotionEvent]:
    """What the rotor did ("move", "arrived", "stopped") since ``since``, brought up to now."""

    def seen(device: Any, now: float) -> list[MotionEvent]:
        device.state(now)  # an arrival is logged when the emulator next looks at the clock
        return [e for e in device.events if e.kind in kinds and e.time_s >= since]

    return emu.call(seen)


def status_doc(rig: Rig) -> dict[str, Any]:
    return json.loads(rig.retained()["rotor/status"])


def turn(rig: Rig, topic: str, payload: str, raw_deg: float) -> tuple[list[bytes], dict[str, Any]]:
    """Publish a command and wait until the rotor stands at ``raw_deg`` (its own scale) and the
    bridge says idle there; the frames it took and the retained status."""
    emu = rig.emus["tower"]
    t = time.monotonic()
    rig.probe.publish(topic, payload)
    emu.wait_for(
        lambda s: not s.is_moving and abs(s.az_deg - raw_deg) <= 1 and not s.in_brake_delay, 15
    )

    def idle_there(m: Any) -> bool:
        doc = json.loads(m.payload)
        return doc["state"] == "idle" and abs(doc.get("raw_bearing", doc["bearing"]) - raw_deg) <= 1

    rig.probe.wait_for("rotor/status", idle_there, timeout_s=10, after=t)
    return [f.data for f in motion_frames(emu, t)], status_doc(rig)


# -- the independent great-circle reference ------------------------------------------------------
def locator_centre(locator: str) -> tuple[float, float]:
    """(latitude, longitude) of the centre of a 6-character Maidenhead square: field 20x10 deg
    from 180 W / 90 S, square 2x1 deg, subsquare 5'x2.5', each pair longitude first."""
    up = locator.upper()
    lon = -180 + (ord(up[0]) - ord("A")) * 20 + int(up[2]) * 2 + (ord(up[4]) - ord("A")) * 5 / 60
    lat = -90 + (ord(up[1]) - ord("A")) * 10 + int(up[3]) * 1 + (ord(up[5]) - ord("A")) * 2.5 / 60
    return lat + 2.5 / 60 / 2, lon + 5 / 60 / 2


def reference_path(a: tuple[float, float], b: tuple[float, float]) -> tuple[float, float]:
    """(initial bearing in degrees, distance in km) from ``a`` to ``b`` on a sphere, by vectors:
    the direction to b projected on the tangent plane at a, read against a's north and east."""

    def unit(lat_deg: float, lon_deg: float) -> tuple[float, float, float]:
        la, lo = math.radians(lat_deg), math.radians(lon_deg)
        return (math.cos(la) * math.cos(lo), math.cos(la) * math.sin(lo), math.sin(la))

    def dot(u: tuple[float, ...], v: tuple[float, ...]) -> float:
        return sum(x * y for x, y in zip(u, v, strict=True))

    pa, pb = unit(*a), unit(*b)
    la, lo = math.radians(a[0]), math.radians(a[1])
    north = (-math.sin(la) * math.cos(lo), -math.sin(la) * math.sin(lo), math.cos(la))
    east = (-math.sin(lo), math.cos(lo), 0.0)
    cos_c = dot(pa, pb)
    toward = tuple(y - cos_c * x for x, y in zip(pa, pb, strict=True))
    bearing = math.degrees(math.atan2(dot(toward, east), dot(toward, north))) % 360
    cross = (
        pa[1] * pb[2] - pa[2] * pb[1],
        pa[2] * pb[0] - pa[0] * pb[2],
        pa[0] * pb[1] - pa[1] * pb[0],
    )
    angle = math.atan2(math.sqrt(dot(cross, cross)), cos_c)
    return bearing, EARTH_RADIUS_KM * angle


def angle_between(a: float, b: float) -> float:
    return abs((a - b + 180) % 360 - 180)


def ap_value(frame: bytes) -> int:
    assert frame.startswith(b"AP1") and frame.endswith(b"\r"), frame
    return int(frame[3:6])


# -- an offset scale, presets, park -------------------------------------------------------------
def test_a_south_centred_rotor_reads_and_takes_true_bearings(rig: Rig) -> None:
    rig.add("tower", emu={**QUICK_EMU, "start_az_deg": 10}, **QUICK_BRIDGE, **SOUTH)
    start(rig)
    rig.probe.wait_for("rotor/status", lambda m: json.loads(m.payload)["state"] == "idle")
    snap = rig.retained()
    assert snap["rotor/bearing"] == b"190"  # raw 10 on a south-centred scale
    status = json.loads(snap["rotor/status"])
    assert (status["bearing"], status["raw_bearing"], status["overlap"]) == (190, 10, None)
    assert json.loads(snap["rotor/presets"]) == {"JA": 330, "EU": 45}
    info = json.loads(snap["rotor/info"])  # for a client far from the station: true bearings
    assert (info["model"], info["azimuth_range"], info["park"]) == ("rotorez", [0, 360], [0, None])

    frames, status = turn(rig, "rotor/target", "270", 90)
    assert frames == [b"AP1090\r"]  # store and go (CR), in the controller's own scale
    assert rig.retained()["rotor/bearing"] == b"270"
    assert (status["bearing"], status["raw_bearing"]) == (270, 90)

    frames, status = turn(rig, "rotor/preset", "JA", 150)
    assert frames == [b"AP1150\r"]  # JA = 330 true
    assert rig.retained()["rotor/bearing"] == b"330"
    assert (status["bearing"], status["raw_bearing"], status["parked"]) == (330, 150, False)

    frames, status = turn(rig, "rotor/park", "PARK", 180)
    assert frames == [b"AP1180\r"]  # park_az_deg 0 true
    assert rig.retained()["rotor/bearing"] == b"0"
    assert (status["bearing"], status["raw_bearing"], status["parked"]) == (0, 180, True)
    assert status["last_command_source"] == "mqtt"


def test_a_target_in_a_keep_out_sector_is_refused_on_mqtt_and_rotctld(rig: Rig) -> None:
    port = free_port()
    emu = rig.add(
        "tower", emu={**QUICK_EMU, "start_az_deg": 10}, rotctld_port=port, **QUICK_BRIDGE, **SOUTH
    )
    start(rig)
    t = time.monotonic()
    rig.probe.publish("rotor/target", "210")  # raw 30: legal for the controller, kept out here
    err = json.loads(rig.probe.wait_for("rotor/error", after=t).payload)
    assert err["kind"] == "refused" and err["command"] == "target '210'"
    assert "keep-out" in err["message"] and "210" in err["message"], err
    with connect(port) as sock:
        for az in (b"210", b"200", b"220"):  # inside, and both edges (edges included)
            ask(sock, b"P " + az + b" 0\n", b"RPRT -9\n")  # RIG_ERJCTED: the bridge said no
        ask(sock, b"p\n", b"190.00\n0.00\n")  # still where it was, in true bearings
    rotctld_err = json.loads(
        rig.probe.wait_for("rotor/error", lambda m: b"rotctld" in m.payload, after=t).payload
    )
    assert "keep-out" in rotctld_err["message"], rotctld_err
    assert motion_frames(emu) == []
    truth = emu.state()
    assert not truth.is_moving and truth.az_deg == 10
    # nothing refused was kept for later: the next legal target is the first thing on the line
    frames, _ = turn(rig, "rotor/target", "230", 50)
    assert [f.data for f in motion_frames(emu)] == frames == [b"AP1050\r"]


# -- targets by locator --------------------------------------------------------------------------
def test_a_locator_target_turns_to_the_great_circle_bearing_short_and_long(rig: Rig) -> None:
    emu = rig.add("tower", emu={**QUICK_EMU, "start_az_deg": 0}, **QUICK_BRIDGE)
    start(rig, station_locator="JO62qm")
    short_deg, distance_km = reference_path(locator_centre("JO62qm"), locator_centre("PM95vq"))
    long_deg = (short_deg + 180) % 360
    long_km = 2 * math.pi * EARTH_RADIUS_KM - distance_km

    for payload, path, want_deg, want_km in (
        ('{"locator": "PM95vq"}', "short", short_deg, distance_km),
        ('{"locator": "PM95vq", "path": "long"}', "long", long_deg, long_km),
    ):
        t = time.monotonic()
        frames, status = turn(rig, "rotor/target", payload, round(want_deg))
        (frame,) = frames
        assert angle_between(ap_value(frame), want_deg) <= 1, (frame, want_deg)
        assert angle_between(emu.state().az_deg, want_deg) <= 1
        assert angle_between(float(rig.retained()["rotor/bearing"]), want_deg) <= 1
        assert angle_between(status["bearing"], want_deg) <= 1

        def aimed(m: Any, path: str = path) -> bool:
            return json.loads(m.payload).get("target_info", {}).get("path") == path

        info = json.loads(rig.probe.wait_for("rotor/status", aimed, after=t).payload)
        info = info["target_info"]
        assert info["locator"] == "PM95vq"
        assert abs(info["distance_km"] - want_km) <= 0.01 * want_km, (info, want_km)
        assert angle_between(info["short_path_deg"], short_deg) <= 1, info
        assert angle_between(info["long_path_deg"], long_deg) <= 1, info


# -- auto-park -----------------------------------------------------------------------------------
def test_auto_park_after_the_quiet_spell_and_a_command_during_the_park_wins(rig: Rig) -> None:
    emu = rig.add("tower", emu={**PARKING_EMU, "start_az_deg": 100}, **PARKING)
    start(rig)
    t_cmd = time.monotonic()
    rig.probe.publish("rotor/target", "110")
    park = emu.wait_for_frame(PARK_FRAME, timeout_s=15)
    arrived = events(emu, t_cmd, "arrived")[0].time_s
    assert park.outcome == "executed"
    assert [f.data for f in motion_frames(emu)] == [b"AP1110\r", PARK_FRAME]
    assert park.time_s - t_cmd >= 5.0, "parked before the quiet spell was over"
    assert arrived < park.time_s, "parked before it arrived"  # (later: a busy machine's timer)
    rig.probe.wait_for(
        "rotor/status",
        lambda m: json.loads(m.payload)["last_command_source"] == "auto-park",
        after=park.time_s - 0.5,
    )

    emu.wait_for(lambda s: s.is_moving and s.az_deg < 95, 5)  # the park is under way
    t = time.monotonic()
    rig.probe.publish("rotor/target", "120")
    final = emu.wait_for(
        lambda s: not s.is_moving and abs(s.az_deg - 120) <= 0.5 and not s.in_brake_delay, 15
    )
    assert final.az_deg == 120
    # stopped first (the Rotor-EZ drops a bearing while turning), then the new target: never
    # the park again, and the rotor never got to the park position
    assert [f.data for f in motion_frames(emu, park.time_s + 1e-6)] == [b";", b"AP1120\r"]
    rests = [e.az_deg for e in events(emu, park.time_s, "arrived", "stopped")]
    assert len(rests) == 2 and 1 < rests[0] < 95 and rests[1] == 120, rests

    def idle_at_120(m: Any) -> bool:
        doc = json.loads(m.payload)
        return doc["state"] == "idle" and doc["bearing"] == 120

    status = json.loads(rig.probe.wait_for("rotor/status", idle_at_120, after=t).payload)
    assert status["last_command_source"] == "mqtt" and status["parked"] is False


def test_no_auto_park_while_someone_turns_the_rotor_by_hand(rig: Rig) -> None:
    emu = rig.add("tower", emu={**PARKING_EMU, "start_az_deg": 100}, **PARKING)
    start(rig)
    t_hand = time.monotonic()
    emu.manual_rotate(300)  # the front panel: 200 degrees at 40 deg/s, 5 s
    park = emu.wait_for_frame(PARK_FRAME, timeout_s=20)
    assert park.outcome == "executed", f"the park was sent while the hand turned it: {park}"
    rest = events(emu, t_hand, "arrived", "stopped")[0]
    assert (rest.kind, round(rest.az_deg)) == ("arrived", 300), f"the hand was cut short: {rest}"
    # the spell began when the controller first answered: it ran out while the hand turned it
    answered = emu.frames("query")[0].time_s
    assert answered + 5.0 < rest.time_s - 0.2, (answered, t_hand, rest)
    # nothing went to the controller while the hand turned it, and the park came only after
    # a whole quiet spell from the hand's last move
    assert [f.data for f in motion_frames(emu)] == [PARK_FRAME]
    assert park.time_s - rest.time_s >= 4.8, "parked before the spell after the hand's move"
