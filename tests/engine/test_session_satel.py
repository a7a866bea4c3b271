"""A SatEL in virtual time: a controller that must hear nothing but a stop while it slews.

The SatEL answers nothing while it moves and prints a status report when the move is over
(protocols/satel.md). Input while it slews can wedge it (the emulator logs every such byte as
"misuse: input while slewing"), so the session sends only ``s`` then (session rule 8). A report
that does not come is handled by slew.py: stop, ask, send the target again; the second time,
give it up; a controller whose clock went back meanwhile restarted, and is sent nothing
(controller.py rule 14). Its own clock ticks every second and rides along in the status
without causing one (status.py rule 4).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from datetime import UTC, datetime

import pytest

from bridge.core.model import MotionState, Origin, Source, Target
from bridge.emulators.satel import Outcome
from bridge.session.slew import SLEW_STOP_TRIES
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING


def ready(rig: Rig, **kw: object) -> VirtualRotator:
    v = rig("satel", **kw)
    v.run_until_state(IDLE, 30)
    return v


def slewing(v: VirtualRotator) -> bool:
    return v.device.state(v.now).slewing


def settled_at(az: float, el: float) -> Callable[[VirtualRotator], bool]:
    def there(v: VirtualRotator) -> bool:
        truth = v.truth()
        return v.state is IDLE and not truth.is_moving and (truth.az_deg, truth.el_deg) == (az, el)

    return there


def slews(v: VirtualRotator) -> list[tuple[float, float]]:
    """When each slew ran, from the emulator's motion events (start, end)."""
    spans: list[tuple[float, float]] = []
    start: float | None = None
    for e in v.device.events:
        if e.kind == "move" and e.detail.startswith("command"):
            start = e.time_s
        elif e.kind in ("arrived", "stopped") and start is not None:
            spans.append((start, e.time_s))
            start = None
    if start is not None:
        spans.append((start, float("inf")))
    return spans


def assert_nothing_but_stops_while_slewing(v: VirtualRotator) -> None:
    assert v.device.misuse_frames() == []
    for start, end in slews(v):
        inside = [f.data for f in v.frames() if start < f.time_s < end]
        assert set(inside) <= {b"s"}, f"input during the slew {start:.2f}..{end:.2f}: {inside}"


def points(v: VirtualRotator, since: float = float("-inf")) -> list[bytes]:
    return [f.data for f in v.frames(Outcome.SLEW, since=since)]


@pytest.mark.parametrize("asked", [(126.0, 36.0), (124.0, 34.0)])
def test_a_satel_turned_as_built_reaches_the_step_nearest_a_target(
    rig: Rig, asked: tuple[float, float]
) -> None:
    """protocols/satel.py rule 7: its rotors move in ten-degree steps, so a target between them
    goes out as the nearest step and ends there, said by no error. An emulator turned as built
    (rule 10 there): sent as asked, 126/36 stopped at 120/30, its report was taken for an old
    one, the slew was stopped as overdue, sent again and the target given up (six errors);
    124/34 ended in a stall 4 degrees short."""
    v = ready(rig, emulator={"step_deg": 10})
    v.target(*asked)
    step = (130.0, 40.0) if asked[0] > 125 else (120.0, 30.0)
    v.run_until(settled_at(*step), 120, f"at {step}")
    v.run_for(60)  # as long again as any slew's bound: nothing more comes of it
    assert points(v) == [b"p%d %d\r" % step]
    assert v.errors() == []
    assert [f for f in v.frames("stop") if f.time_s > 1.0] == []  # (the one at connect)
    assert (v.status.bearing_deg, v.status.elevation_deg) == step
    assert (v.status.target_az_deg, v.status.target_el_deg) == (None, None)
    assert v.state is IDLE and not v.status.estimated


def test_a_redirect_stops_the_slew_and_sends_the_new_point_once_still(rig: Rig) -> None:
    v = ready(rig)
    v.target(200, 40)
    v.run_for(10)
    assert slewing(v)
    s = v.status
    assert s.state is MOVING and s.estimated and s.bearing_deg is not None
    t = v.now
    v.target(50, 20)
    v.run_until(settled_at(50, 20), 120, "at 50/20")

    assert points(v) == [b"p200 40\r", b"p50 20\r"]
    after = [f.data for f in v.frames(since=t) if f.data != b"z"]
    assert after[0] == b"s" and after[-2:] == [b"g", b"p50 20\r"]
    assert len(slews(v)) == 2
    assert_nothing_but_stops_while_slewing(v)
    assert v.errors() == []


def test_a_lost_report_of_a_slew_that_arrived_is_ridden_out(rig: Rig) -> None:
    v = ready(rig)
    v.target(100, 20)
    v.run_until(slewing, 5, "slewing")
    v.set_silent(True)  # the report at the end of this slew is lost on the line
    v.run_until(lambda v: not slewing(v), 60)
    v.run_for(0.5)
    v.set_silent(False)
    lost_at = v.now
    v.run_until(settled_at(100, 20), 120, "idle at 100/20")
    v.run_for(10)

    late, asked = v.errors()
    assert late.kind == "serial" and late.message.startswith("no report from the controller")
    assert "az_speed_deg_s" in late.message  # it names the setting to fix a slow rotor
    assert asked.message == "no report after the stopped slew; asking the controller"
    # stopped (a SatEL at rest does not report a stop: every try is made), then asked
    after = [f.data for f in v.frames(since=lost_at)]
    assert after[: SLEW_STOP_TRIES + 1] == [b"s"] * SLEW_STOP_TRIES + [b"z"]
    assert points(v) == [b"p100 20\r"]  # it is there: nothing to send again
    assert all(s.available for s in v.published(since=lost_at))  # never called offline
    assert_nothing_but_stops_while_slewing(v)


# the user set the rotor faster than it is: its slews outlast the wait for their report
TOO_FAST = {"az_speed_deg_s": 30, "el_speed_deg_s": 15}


def test_a_slew_that_outlasts_its_report_bound_is_stopped_asked_and_sent_again(
    rig: Rig,
) -> None:
    v = ready(rig, settings=TOO_FAST)
    t = v.now
    v.target(200, 20)
    v.run_until(settled_at(200, 20), 120, "at 200/20")

    [late] = v.errors()
    assert late.kind == "serial" and "then going on to the target" in late.message
    assert points(v) == [b"p200 20\r", b"p200 20\r"]
    stopped = [e for e in v.device.events if e.kind == "stopped"]
    assert len(stopped) == 1 and 0 < stopped[0].az_deg < 200  # stopped mid-way, then resumed
    after = [f.data for f in v.frames(since=t) if f.data not in (b"z", b"g")]
    assert after == [b"p200 20\r", b"s", b"p200 20\r"]
    assert_nothing_but_stops_while_slewing(v)


def test_a_target_whose_report_is_lost_twice_is_given_up(rig: Rig) -> None:
    v = ready(rig, settings=TOO_FAST)
    v.target(200, 20)
    v.run_until(lambda v: len(points(v)) == 2, 120, "sent again")
    v.set_silent(True)  # and this time the report is lost
    v.run_until(lambda v: not slewing(v), 60)
    v.run_for(0.5)
    v.set_silent(False)
    v.run_for(60)

    first, second, *rest = v.errors()
    assert "then going on to the target" in first.message
    assert second.kind == "serial" and "giving the target up" in second.message
    assert second.command == "target az 200 el 20"
    assert [e.kind for e in rest] == ["serial"]  # "no report after the stopped slew; asking"
    assert points(v) == [b"p200 20\r", b"p200 20\r"]  # not a third time
    assert v.state is IDLE and v.status.target_az_deg is None
    assert_nothing_but_stops_while_slewing(v)


def test_a_jammed_slew_is_tried_twice_then_given_up_and_stopped(rig: Rig) -> None:
    v = ready(rig)
    v.target(200, 20)
    v.run_for(5)
    v.jam()
    v.run_for(300)

    first, second = v.errors()
    assert "then going on to the target" in first.message
    assert "giving the target up" in second.message
    assert points(v) == [b"p200 20\r", b"p200 20\r"]
    assert not v.truth().is_moving  # the motors are not left running against the jam
    assert_nothing_but_stops_while_slewing(v)


def clock(text: str | None) -> datetime:
    assert text is not None
    return datetime.strptime(text, "%Y/%m/%d %H:%M:%S")


def test_an_idle_satel_whose_clock_ticks_is_not_republished(rig: Rig) -> None:
    v = ready(rig, settings={"idle_poll_interval_s": 1.0, "silence_timeout_s": 3.0})
    t = v.now
    shown = clock(v.status.controller_time)
    v.run_for(120)

    assert len(v.frames(Outcome.STATUS, since=t)) >= 110  # read every second, a new time each
    assert v.published(since=t + 1e-9) == []
    # the clock rides along in the next status a user would notice
    v.target(10, 10)
    v.run_for(0.5)
    assert v.status.state is MOVING
    assert (clock(v.status.controller_time) - shown).total_seconds() >= 119


def test_a_stream_of_targets_ends_at_the_last_without_input_into_a_slew(rig: Rig) -> None:
    v = ready(rig)
    for az in range(100, 200):  # 100 targets, 10 ms apart
        v.target(az, 10)
        v.run_for(0.01)
    v.run_until(settled_at(200, 10), 300, "at 200/10")  # 199's step (satel.py rule 7)

    assert 1 <= len(points(v)) <= 3 and points(v)[-1] == b"p200 10\r"
    assert_nothing_but_stops_while_slewing(v)


def test_a_second_report_in_the_same_exchange_is_no_reading(rig: Rig) -> None:
    """link.py rule 9 for the SatEL: a whole second report, saying 180 deg, right behind the
    real one of one exchange (a value garbled inside a report already spoils it: satel.py rule
    3). Neither is taken: no 180 published, no move in rotor health, the controller asked
    again."""
    v = ready(rig)
    v.run_for(10)
    bearing, health = v.status.bearing_deg, v.status.health
    assert health is not None and bearing is not None and abs(bearing - 180.0) > 1
    second = (
        b"Motion ENABLED\r\nMode 0 - azimuth break at NORTH\r\nTime: 2001/00/00 00:00:07\r\n"
        b"Azimuth = 180     Absolute = 180\r\nElevation = 000\r\n\r\n"
        b"Number of stored positions: 00\r\n"
    )
    seen = bytearray()
    glitched: list[float] = []

    def glitch(data: bytes, now: float) -> bytes:
        seen.extend(data)
        if glitched or not re.search(rb"stored positions: \d+\r\n$", seen):
            return data
        glitched.append(now)
        return data + second

    v.to_host = glitch
    t = v.now
    v.run_for(30)
    assert glitched
    assert {s.bearing_deg for s in v.published(since=t)} <= {bearing}
    assert v.status.health is not None and v.status.health.moves == health.moves
    assert v.state is IDLE and v.status.bearing_deg == bearing


def test_a_report_that_lost_a_digit_on_the_line_is_never_published(rig: Rig) -> None:
    """protocols/satel.py rule 3: ``Azimuth = 123`` with its 3 lost read as a bearing of 12 (the
    rotor at 123: turned there by hand, r and s on a terminal)."""
    v = rig("satel", emulator={"start_az_deg": 123})
    v.run_until_state(IDLE, 30)
    v.run_for(5)
    pattern, seen = b"Azimuth = 123", {"tail": b"", "lost": False}

    def drop(data: bytes, now: float) -> bytes:
        if seen["lost"]:
            return data
        seen["tail"] = (seen["tail"] + data)[-len(pattern) :]
        if seen["tail"] == pattern:  # the 3 of 123 just came: lost on the line
            seen["lost"] = True
            return data[:-1]
        return data

    v.to_host = drop
    t = v.now
    v.run_until(lambda h: seen["lost"], 30, "a byte lost")
    v.run_for(5)
    assert {s.bearing_deg for s in v.published(since=t)} - {None} <= {123.0}


def test_a_stop_whose_report_is_spoiled_shows_no_bearing_of_before_the_slew(rig: Rig) -> None:
    """controller.py ``_unseen``: a STOP in a silent slew, its report spoiled by one byte: the
    slew ends unseen, and the status showed the last reading from before the slew (0 degrees,
    not estimated, while the rotor stood near 60) until the report asked again came."""
    v = rig("satel")
    v.run_until_state(IDLE, 30)
    v.target(200, 40)
    v.run_for(10)
    t, tail, hit = v.now, {"b": b""}, {"done": False}

    def garble(data: bytes, now: float) -> bytes:  # one byte of the next report: b -> x
        out = bytearray()
        for byte in data:
            if not hit["done"] and tail["b"].endswith(b"Num") and byte == ord("b"):
                byte, hit["done"] = ord("x"), True
            tail["b"] = (tail["b"] + bytes([byte]))[-8:]
            out.append(byte)
        return bytes(out)

    v.to_host = garble
    v.stop()
    v.run_until(lambda h: hit["done"], 30, "the stop's report garbled")
    v.to_host = None
    v.run_until(lambda h: h.state is IDLE, 30, "idle")
    shown = [s for s in v.published(since=t) if s.bearing_deg is not None and not s.estimated]
    assert shown and all(abs(s.bearing_deg - v.truth().az_deg) < 3 for s in shown)


def test_one_lost_reply_after_a_stop_sends_no_second_stop(rig: Rig) -> None:
    """motion.py ``stop_again`` (an attack pass): a new target mid-slew, the stop, the report
    after it (a movement since the stop), then the answer to the next poll lost. A stop's
    repeat asks for a movement in the last ``settle_s``: the target's own way to it did not,
    and a second stop went to a rotor at rest, the target a settle time later."""
    v = ready(rig)
    v.target(170)
    v.run_for(8)
    t0 = v.now
    v.target(90)
    controller = v.session.controller
    link = controller.link
    assert link is not None
    v.run_until(lambda h: link.slew is None and b"s" in h.sent(since=t0), 10, "stopped")
    motion = controller.motion  # (the report after the stop: a movement since it)
    assert motion.stop_sent_t is not None and (motion.last_move_t or 0) > motion.stop_sent_t
    v.set_silent(True)
    v.run_for(1.0)  # one poll's answer lost
    v.set_silent(False)
    v.run_until(lambda h: b"p90 0\r\n" in h.sent(since=t0), 10, "the new point sent")
    assert [w.data for w in v.writes if w.t >= t0 and w.data == b"s"] == [b"s"]


def test_a_point_stored_before_the_bridge_connected_never_turns_the_rotor(rig: Rig) -> None:
    # another program loaded a pass into the controller's memory (manual: ``2YYYY/MM/DD ...``)
    # before the bridge took the port; the bridge's ``g`` switches automatic motion on, and
    # the point, due 80 s later by the clock the bridge sets, would turn a locked rotor to
    # 200/30 by itself, unseen (it answers no poll while it slews)
    v = rig("satel", connect=False, locked=True)
    due = datetime.fromtimestamp(v.wall() + 80, UTC).strftime("%Y/%m/%d %H:%M:%S")
    v.device.receive(due.encode() + b" 200 30\r", v.now)
    assert len(v.device.state(v.now).stored_points) == 1
    v.link_up()
    v.run_until_state(IDLE, 30)
    v.run_for(120)
    truth = v.truth()
    assert (truth.az_deg, truth.el_deg) == (0.0, 0.0)
    assert v.device.state(v.now).stored_points == ()
    assert not [e for e in v.device.events if e.kind == "move"]


def test_a_satel_power_cycled_mid_slew_is_not_sent_its_target_again(rig: Rig) -> None:
    v = ready(rig)
    v.target(200, 40)
    v.run_for(10)
    assert slewing(v)
    cut = v.now
    v.power_cycle()  # its report never comes; its clock starts again at 2001/00/00
    stood = v.truth()
    v.run_for(200)

    # the wait for the report, the stops, one question: then nothing that moves it
    after = [f.data for f in v.frames(since=cut) if f.data != b"z"]
    assert after[:SLEW_STOP_TRIES] == [b"s"] * SLEW_STOP_TRIES
    assert set(after[SLEW_STOP_TRIES:]) <= {b"g"}  # motion on again (it restarted with it off)
    assert points(v) == [b"p200 40\r"]  # not sent again
    assert (v.truth().az_deg, v.truth().el_deg) == (stood.az_deg, stood.el_deg)
    *_, restarted = v.errors()
    az, el = round(stood.az_deg), round(stood.el_deg)
    assert restarted.kind == "serial"
    assert re.fullmatch(
        rf"the controller restarted mid-turn \(its clock went back, to 2001/00/00 00:\d\d:\d\d\) "
        rf"at {az}°, elevation {el}°: its turn to 200°, elevation 40° was not resumed: send the "
        "target again",
        restarted.message,
    ), restarted.message
    assert [e for e in v.errors() if "restarted mid-turn" in e.message] == [restarted]
    s = v.status
    assert s.state is IDLE and s.target_az_deg is None and s.health.stalls == 0
    assert_nothing_but_stops_while_slewing(v)


def test_a_satel_restarted_mid_slew_whose_clock_line_is_garbled_is_sent_its_target_again(
    rig: Rig,
) -> None:
    v = ready(rig)
    v.target(200, 40)
    v.run_for(10)
    v.power_cycle()
    seen = bytearray()

    def garble_the_clock(data: bytes, now: float) -> bytes:  # its first report's clock, once
        seen.extend(data)
        if seen.endswith(b"Time: 2") and seen.count(b"Time: ") == 1:
            return data[:-1] + b"x"
        return data

    v.to_host = garble_the_clock
    v.run_until(lambda v: len(points(v)) == 2, 200, "sent again")

    # nothing it said could tell a restart: a lost report, as the docs say
    assert points(v) == [b"p200 40\r", b"p200 40\r"]
    assert not [e for e in v.errors() if "restarted mid-turn" in e.message]
    assert_nothing_but_stops_while_slewing(v)


def test_a_satel_power_cycled_mid_slew_then_redirected_is_not_sent_the_new_point(
    rig: Rig,
) -> None:
    # a newer target (a tracking step, a second user) stops the slew: its report never comes
    # either, and the first reading after the stops must judge the clock as a lost report's
    v = ready(rig)
    v.target(200, 40)
    v.run_for(10)
    v.power_cycle()
    stood = v.truth()
    cut = v.now
    v.target(100, 20)
    v.run_for(200)

    after = [f.data for f in v.frames(since=cut) if f.data != b"z"]
    assert after[:SLEW_STOP_TRIES] == [b"s"] * SLEW_STOP_TRIES
    assert set(after[SLEW_STOP_TRIES:]) <= {b"g"}
    assert points(v) == [b"p200 40\r"]  # the newer point is not sent to the restarted unit
    assert (v.truth().az_deg, v.truth().el_deg) == (stood.az_deg, stood.el_deg)
    [said] = [e for e in v.errors() if "restarted mid-turn" in e.message]
    assert said.kind == "serial" and said.command == "target az 100 el 20"
    assert re.fullmatch(
        r"the controller restarted mid-turn \(its clock went back, to 2001/00/00 00:\d\d:\d\d\) "
        r"at \d+°, elevation \d+°: its turn to 200°, elevation 40° was not resumed: send the "
        "target again",
        said.message,
    ), said.message
    s = v.status
    assert s.state is IDLE and s.target_az_deg is None and s.health.stalls == 0
    assert_nothing_but_stops_while_slewing(v)


def test_a_target_sent_while_a_restarted_satel_is_asked_where_it_is_is_dropped_and_said(
    rig: Rig,
) -> None:
    # the report is late, the target put back to go again; a newer one replaces it before the
    # first reading comes: the restart is still said, and neither goes to the restarted unit
    v = ready(rig)
    v.target(200, 40)
    v.run_for(10)
    v.power_cycle()
    stood = v.truth()
    v.run_until(
        lambda v: any(e.message.startswith("no report from the controller") for e in v.errors()),
        200,
        "the report is late",
    )
    v.target(100, 20)
    v.run_for(200)

    assert points(v) == [b"p200 40\r"]
    assert (v.truth().az_deg, v.truth().el_deg) == (stood.az_deg, stood.el_deg)
    [said] = [e for e in v.errors() if "restarted mid-turn" in e.message]
    assert said.kind == "serial" and said.command == "target az 100 el 20"
    assert "its turn to 200°, elevation 40° was not resumed" in said.message
    s = v.status
    assert s.state is IDLE and s.target_az_deg is None and s.health.stalls == 0
    assert_nothing_but_stops_while_slewing(v)


# a storm (wind.py): its park goes out whatever else waits
STORM = {"wind_topic": "weather/wind", "wind_park_above": 60, "wind_release_below": 40}
STORM |= {"wind_park_az_deg": 90}


def wind_kmh(v: VirtualRotator, kmh: float) -> None:
    v.mailbox.put_wind(kmh)
    v._take()


def test_a_storms_park_waiting_when_a_restarted_satel_is_read_still_goes(rig: Rig) -> None:
    # the storm begins mid-slew: its park stops the slew and waits; the restart is said, yet
    # the park is no user's turn to abandon (wind.py: the storm's park goes on)
    v = ready(rig, settings=STORM)
    wind_kmh(v, 30.0)
    v.target(200, 40)
    v.run_for(10)
    v.power_cycle()
    wind_kmh(v, 75.0)
    v.run_until(lambda v: v.status.parked, 300, "parked for the storm")

    assert points(v)[0] == b"p200 40\r" and points(v)[-1].startswith(b"p90 ")
    [said] = [e for e in v.errors() if "restarted mid-turn" in e.message]
    # the park goes on, so the error names no command as dropped (a cold review: it named
    # the park, 'target az 90', as the restart's dropped target while the rotor parked)
    assert said.command is None
    assert abs(v.truth().az_deg - 90.0) <= 0.5
    assert_nothing_but_stops_while_slewing(v)


def test_an_elevation_alone_sent_while_a_late_slews_target_waits_keeps_its_azimuth(
    rig: Rig,
) -> None:
    """mailbox.py rule 2, core/model.py ``combine``: an azimuth, then an elevation alone, from
    one sender, is one target. DL1ABC's 200/20 outlasts its report's bound (a rotor slower
    than set, no restart): stopped, asked, put back to go again (slew.py rule 4); DL1ABC's
    elevation 40 meanwhile was not taken with the azimuth put back (that one named no
    sender, since the check that only one sender's halves combine), and the rotor went to
    where the stop left it, at elevation 40, short of the 200 DL1ABC asked (a cold review)."""
    v = ready(rig, settings=TOO_FAST)
    who = Origin(Source.MQTT, "DL1ABC")
    v.command(Target(200, 20, origin=who))
    v.run_until(
        lambda v: any("then going on to the target" in e.message for e in v.errors()),
        120,
        "the report is late",
    )
    assert v.session.targets.pending is not None  # put back, to go again
    v.command(Target(None, 40, origin=who))
    v.run_until(lambda v: len(points(v)) == 2, 120, "sent again")
    v.run_until(lambda v: v.state is IDLE and not v.truth().is_moving, 120, "at rest")
    assert points(v)[-1] == b"p200 40\r"
    assert (v.truth().az_deg, v.truth().el_deg) == (200, 40)
    assert_nothing_but_stops_while_slewing(v)


def test_a_connect_into_a_slew_stops_it_once_and_sets_up_after_its_report(rig: Rig) -> None:
    """session/link.py rule 14: the connect's stop answered by the stopped slew's report is
    not written again, and the set-up follows that report, not the stop."""
    v = rig("satel", connect=False, emulator={"corrupt_on_misuse": True})
    v.device.receive(b"g", v.now)  # the process before this one set the box slewing
    v.device.receive(b"p200 60\r\n", v.now)
    v.run_for(2)  # (the bridge restarts mid-slew: not a deadline)
    v.link_up()
    v.run_for(5)  # (the connect's exchanges: not a deadline)
    sent = [w.data for w in v.writes]
    assert sent[:3] == [b"s", b"x", b"?"], sent
    assert sent.count(b"s") == 1, sent
    received, report_t = b"", None
    for t, chunk in v.received:
        received += chunk
        if b"Number of stored" in received:
            report_t = t
            break
    assert report_t is not None
    x_t = next(w.t for w in v.writes if w.data == b"x")
    assert x_t > report_t  # (the stopped slew's report whole before the set-up)
    assert v.truth().misuse_count == 0 and not slewing(v)
