"""A composite rotator (runtime/composite.py) in virtual time: a Green Heron RT-21 turns the
azimuth, a GS-232B box the elevation, each on its own emulated line, one mailbox and one
status in front (tests/engine/virtual_composite.py). The sky is fixed (SUN_EPOCH) and checked
against the test's own solar formula (tests/support/sky.py)."""

from __future__ import annotations

import itertools
import json
from collections.abc import Iterator
from pathlib import Path

import pytest
import serial

import bridge.app as app
import bridge.feature
from bridge.core.errors import Refused
from bridge.core.model import (
    Control,
    ErrorEvent,
    ErrorKind,
    FeatureCommand,
    MotionState,
    Origin,
    RotatorStatus,
    Source,
    Stop,
    Target,
    describe_command,
)
from bridge.feature import Feature
from bridge.features import FEATURES
from bridge.interfaces.mqtt.groups import Group, Member, status_json
from bridge.protocols.axes import Axis
from bridge.runtime.composite import TWIN_S, CompositeWorker, Composition
from bridge.runtime.port import PortError
from bridge.session.actions import Audit, Report
from bridge.session.follow import Follow, Heard
from bridge.session.mailbox import Mailbox
from bridge.session.parts import Part, Proposal, Scene, Wake
from bridge.session.session import RotatorSession
from bridge.session.tracking import Track
from bridge.settings import RotatorSettings
from bridge.sky import Body, Sky
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine import virtual_composite
from tests.engine.test_catalog import ISS, three_line
from tests.engine.test_follow import STATION
from tests.engine.test_session_tracking import (
    BERLIN,
    SUN_EPOCH,
    a_pass_that,
    off_deg,
    sun_up_somewhere,
)
from tests.engine.virtual_composite import VirtualComposite
from tests.support.sky import sgp4_altaz, sun_altaz

FAST = {
    Axis.AZIMUTH: {"az_speed_deg_s": 6.0},
    Axis.ELEVATION: {"az_speed_deg_s": 6.0, "el_speed_deg_s": 2.5},
}
FINE = {"tolerance_deg": 0.5, "track_step_deg": 1.0}


def online(v: VirtualComposite) -> bool:
    return v.status.available


def test_an_rt21_and_a_gs232b_track_the_sun_within_1_5_degrees() -> None:
    lat, lon = sun_up_somewhere(SUN_EPOCH)
    sky = Sky(lat, lon)
    with VirtualComposite(
        "rt21", "gs232b", settings=FINE, emulators=FAST, sky=sky, wall_epoch_s=SUN_EPOCH
    ) as v:
        v.run_until(online, 10, "both boxes answer")
        v.track(Body.sun())
        assert v.status.tracking is not None and v.status.tracking.body == "sun"

        def on_the_sun(h: VirtualComposite) -> bool:
            sun_az, sun_el = sun_altaz(lat, lon, h.wall())
            az, el = h.az.truth().az_deg, h.el.truth().el_deg
            return off_deg(az, sun_az) <= 1.5 and abs(el - sun_el) <= 1.5

        v.run_until(on_the_sun, 120, "the rotor reaches the sun")
        worst_az = worst_el = 0.0
        end = v.now + 600.0  # ten minutes of rotor time, sampled every second
        while v.now < end:
            v.run_for(1.0)
            sun_az, sun_el = sun_altaz(lat, lon, v.wall())
            worst_az = max(worst_az, off_deg(v.az.truth().az_deg, sun_az))
            worst_el = max(worst_el, abs(v.el.truth().el_deg - sun_el))
        assert worst_az <= 1.5 and worst_el <= 1.5, (worst_az, worst_el)
        # both boxes moved on with the sun, and the status shows each box's axis
        assert len(v.az.frames("move")) >= 2 and len(v.el.frames("move")) >= 3
        status = v.status
        assert status.tracking is not None and status.last_command_source == Source.TRACKING.value
        assert status.bearing_deg is not None and off_deg(status.bearing_deg, sun_az) <= 2.0
        assert status.elevation_deg is not None and abs(status.elevation_deg - sun_el) <= 2.0
        # the elevation box's own azimuth was never turned (protocols/axes.py rule 2)
        assert v.el.truth().az_deg == 0.0
        assert all(w.startswith((b"W000 ", b"C2")) for w in v.el.sent()), v.el.sent()


def test_a_satellite_pass_is_never_flown_flipped_by_the_elevation_box_alone() -> None:
    """tracking.py rule 4: a pass across the north, the elevation box allowed 0..180 (a flip
    would save the azimuth's unwind). Each box's session decided the flip alone: the RT-21
    azimuth box (no elevation) never flips, the GS-232B elevation box flew 180 - el, and the
    antenna faced away from the satellite for the whole pass (an attack pass). Now neither
    flips: the elevation stays below the zenith, and the antenna is on the satellite but for
    the azimuth's one unwind through its stop (60 s at 6 degrees a second)."""
    line1, line2, aos, los = a_pass_that(across_north=True)
    settings = {"az_min_deg": 0, "az_max_deg": 360, "el_min_deg": 0, "el_max_deg": 180}
    sky = Sky(*BERLIN)
    with VirtualComposite(
        "rt21", "gs232b", settings=settings, emulators=FAST, sky=sky, wall_epoch_s=aos - 600
    ) as v:
        v.run_until(online, 10, "both boxes answer")
        v.track(Body.satellite("TESTSAT", line1, line2))
        v.run_until(lambda h: h.wall() >= aos + 30, 700, "the pass under way")
        off_s = seconds = 0
        highest = 0.0
        while v.wall() < los:
            v.run_for(1.0)
            sat_az, sat_el = sgp4_altaz(line1, line2, *BERLIN, v.wall())
            az, el = v.az.truth().az_deg, v.el.truth().el_deg
            assert el is not None
            highest = max(highest, el)
            off_s += max(off_deg(az, sat_az), abs(el - sat_el)) > 5.0
            seconds += 1
        assert highest <= 90.0, highest
        assert off_s <= 60, (off_s, seconds)


def test_one_stop_stops_both_boxes() -> None:
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(200.0, 60.0))
        v.run_until(lambda h: h.status.state is MotionState.MOVING, 5, "moving")
        v.run_for(2.0)
        assert v.az.truth().az_deg > 1.0 and v.el.truth().el_deg > 1.0
        t = v.now
        v.stop()
        assert v.az.sent(since=t) == [b";"]  # the RT-21's stop, in the same instant
        assert v.el.sent(since=t) == [b"S\r"]  # the GS-232B's
        v.run_for(5.0)
        assert [f.outcome for f in v.az.frames(since=t)][:1] == ["stop"]  # each box obeyed
        assert [f.outcome for f in v.el.frames(since=t)][:1] == ["stop"]
        az, el = v.az.truth().az_deg, v.el.truth().el_deg
        v.run_for(10.0)
        assert (v.az.truth().az_deg, v.el.truth().el_deg) == (az, el)  # still
        assert az < 100.0 and el < 40.0  # short of the target: stopped on the way
        assert v.status.state is not MotionState.MOVING


def test_an_unplugged_box_takes_the_rotator_offline_and_the_other_still_stops() -> None:
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(200.0, 60.0))
        v.run_for(2.0)
        v.el.link_down()
        v.run_for(0.1)
        # (offline; but the azimuth box is read turning on: shown so, composite.py rule 3)
        assert not v.status.available and v.status.state is MotionState.MOVING
        assert v.status.last_error == "virtual port unplugged"
        t = v.now
        v.stop()
        assert v.az.sent(since=t) == [b";"]  # the box still plugged stops at once
        v.run_for(3.0)
        assert v.status.state is MotionState.OFFLINE  # (the azimuth at rest, the other out)
        az = v.az.truth().az_deg
        v.run_for(3.0)
        assert v.az.truth().az_deg == az < 100.0  # still, short of the target
        v.el.link_up()  # replugged: the stop it was owed is its first frame (behind a line
        # end that ends a half frame the unplug left: gs232.py rule 6)
        assert v.el.sent(since=v.now)[:1] == [b"\rS\r"]
        v.run_until(online, 10, "both boxes answer again")
        assert v.status.state is not MotionState.OFFLINE


def test_a_group_with_a_rotator_whose_azimuth_box_turns_on_alone_says_it_moves() -> None:
    """An attack pass: the elevation box unplugged while the azimuth turned on alone (then a
    turn on its way; since rule 8 stops that, a hand at the azimuth box's panel), the rotator
    was shown offline and not moving, and a group with it and an idle rotator said idle."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.el.link_down()
        v.run_for(1.0)
        v.az.manual_rotate(200.0)
        v.run_for(3.0)
        assert v.az.truth().is_moving and v.status.moving and not v.status.available
        mast = RotatorStatus("mast", state=MotionState.IDLE, bearing_deg=10.0, available=True)
        group = Group("stack", "stack", (Member("sky"), Member("mast")))
        doc = json.loads(status_json(group, {"sky": v.status, "mast": mast}, {}))
        assert doc["moving"] and doc["state"] == "moving" and doc["available"]


def test_a_target_held_back_in_one_box_is_dropped_when_the_other_is_unplugged() -> None:
    """A review: re-targeted mid-turn, the Rotor-EZ box stops first and holds the new azimuth
    for its brake delay; the elevation box was unplugged meanwhile (the rotator offline), and
    when the delay ended the azimuth went out anyway: it turned alone, from 31 to 113 and on."""
    emulators = {Axis.AZIMUTH: {"speed_deg_s": 6.0}, Axis.ELEVATION: FAST[Axis.ELEVATION]}
    with VirtualComposite("rotorez", "gs232b", emulators=emulators) as v:
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(120.0, 20.0))
        v.run_until(lambda h: h.az.truth().az_deg > 30, 30, "turning")
        t = v.now
        v.aim(Target(300.0, 40.0))  # while turning: a stop, the brake delay, then the target
        v.run_for(0.2)
        v.el.link_down()
        v.run_for(0.1)
        assert not v.status.available
        az = v.az.truth().az_deg
        v.run_for(20.0)
        assert [f for f in v.az.sent(since=t) if f.startswith(b"AP1")] == []
        assert v.az.truth().az_deg == pytest.approx(az, abs=2.0)
        assert v.status.last_error == "target dropped: rotator offline"


def test_a_target_handed_out_while_one_box_is_unplugged_moves_neither() -> None:
    """Rule 8: the judge refuses a target while the rotator is offline, but one it took just
    before a box went must not turn the other alone."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.el.link_down()
        v.run_for(0.1)
        az = v.az.truth().az_deg
        v.aim(Target(200.0, 30.0))  # (the harness's judge does not look at the link)
        v.run_for(3.0)
        assert v.az.truth().az_deg == az and not v.az.truth().is_moving
        assert v.status.last_error == "rotator offline"


def test_tracking_ends_in_both_boxes_when_one_box_is_unplugged() -> None:
    lat, lon = sun_up_somewhere(SUN_EPOCH)
    sky = Sky(lat, lon)
    with VirtualComposite("rt21", "gs232b", emulators=FAST, sky=sky, wall_epoch_s=SUN_EPOCH) as v:
        v.run_until(online, 10, "both boxes answer")
        v.track(Body.sun())
        v.run_for(5.0)
        assert v.az.status.tracking is not None and v.el.status.tracking is not None
        v.el.link_down()
        v.run_for(0.5)
        assert v.az.status.tracking is None  # the azimuth does not follow the sun alone
        assert v.status.tracking is None and v.status.tracking_ended == "serial link down"
        v.run_for(30.0)  # (the step it was on is finished: ending tracking stops nothing)
        t, az = v.now, v.az.truth().az_deg
        v.run_for(600.0)
        assert v.az.truth().az_deg == az and v.az.frames("move", since=t) == []


def test_a_track_command_that_reaches_a_box_gone_offline_tracks_no_axis_alone() -> None:
    """composite.py rule 4: the elevation box unplugged after the judge took the command (it
    found the rotator online) refuses it; the azimuth box began tracking the sun alone, and
    went on when the elevation box came back."""
    lat, lon = sun_up_somewhere(SUN_EPOCH)
    with VirtualComposite("rt21", "gs232b", emulators=FAST, sky=Sky(lat, lon)) as v:
        v.run_until(online, 10, "both boxes answer")
        v.el.link_down()
        t = v.now
        v.track(Body.sun())
        v.run_for(5.0)
        v.el.link_up()
        v.run_until(online, 10, "both boxes answer again")
        v.run_for(120.0)
        assert v.az.status.tracking is None and v.el.status.tracking is None
        assert v.status.tracking_ended == "rotator offline"
        assert v.az.frames("move", since=t) == [] and v.el.frames("move", since=t) == []


@pytest.mark.parametrize("aim", [Target(200.0, None), Target(None, 30.0)])
def test_a_target_to_one_axis_after_a_track_command_ends_tracking_in_both_boxes(
    aim: Target,
) -> None:
    """composite.py rule 2: "track sun" and then at once a bearing, taken in one batch (a busy
    lines thread): the bearing is the last word on the whole rotator. An azimuth alone was no
    target for the elevation box, which went on tracking the sun by itself (its elevation
    rotor turned to the sun's) while the status said nothing was tracked (an attack pass)."""
    lat, lon = sun_up_somewhere(SUN_EPOCH)
    with VirtualComposite(
        "rt21", "gs232b", settings=FINE, emulators=FAST, sky=Sky(lat, lon), wall_epoch_s=SUN_EPOCH
    ) as v:
        v.run_until(online, 20, "both boxes answer")
        v.aim(Target(100.0, 10.0))
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > 5, 200, "idle")
        still = Axis.ELEVATION if aim.el_deg is None else Axis.AZIMUTH
        t, before = v.now, v.boxes[still].truth()
        v.mailbox.put_track(Track(Body.sun()))
        v.mailbox.put(v.cfg.aim.judge(aim, v.status.raw_bearing_deg))
        v._take()
        v.run_for(180.0)
        assert v.az.status.tracking is None and v.el.status.tracking is None
        assert v.boxes[still].frames("move", since=t) == []
        after = v.boxes[still].truth()
        assert (after.az_deg, after.el_deg) == (before.az_deg, before.el_deg)


def test_an_azimuth_before_a_satellite_is_looked_up_ends_its_tracking_in_both_boxes(
    tmp_path: Path,
) -> None:
    """composite.py rule 2: ``R/track ISS`` (looked up by the sky worker, tracking.py rule 8),
    then, before the answer, an azimuth: the elevation box, given no target, started tracking
    ISS when its answer came, and drove its elevation from 45 to 180 (the flipped waiting
    position of a satellite below the horizon) by itself (an attack pass)."""
    path = tmp_path / "sats.txt"
    path.write_text(three_line(("ISS (ZARYA)", ISS)))
    lat, lon = sun_up_somewhere(SUN_EPOCH)
    with VirtualComposite(
        "rt21", "gs232b", settings=FINE, emulators=FAST, sky=Sky(lat, lon), wall_epoch_s=SUN_EPOCH
    ) as v:
        for box in v.boxes.values():
            box.sky_delay_s = 0.5  # the look-up takes a moment (a file read)
        v.run_until(online, 20, "both boxes answer")
        v.aim(Target(100.0, 45.0))
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > 5, 200, "idle")
        t = v.now
        lookup = LookupQuestion(TleCatalog(path), "ISS (ZARYA)")
        v.mailbox.put_track(Track(None, Source.MQTT, lookup, "track ISS"))
        v._take()
        v.run_for(0.1)  # the look-up is under way
        v.aim(Target(200.0, None))
        v.run_for(180.0)
        assert v.az.status.tracking is None and v.el.status.tracking is None
        assert v.el.frames("move", since=t) == [] and v.el.truth().el_deg == 45.0


def test_two_rt21_boxes_make_an_az_el_rotator() -> None:
    """Green Heron's az/el pair: one RT-21 box turns the elevation rotor on its one axis."""
    with VirtualComposite("rt21", "rt21", emulators={Axis.ELEVATION: {"az_speed_deg_s": 3.0}}) as v:
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(200.0, 45.5))
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > 5, 120, "idle")
        assert v.az.truth().az_deg == 200.0 and v.el.truth().az_deg == 45.5
        assert [f.data for f in v.el.frames("move")] == [b"AP1045.5\r;"]
        assert (v.status.bearing_deg, v.status.elevation_deg) == (200.0, 45.5)
        t = v.now
        v.aim(Target(None, 10.0))  # the elevation alone: the azimuth box is sent nothing
        v.run_until(lambda h: h.el.truth().az_deg == 10.0, 60, "the elevation turned")
        assert v.az.frames("move", since=t) == []


@pytest.mark.parametrize(
    "model", ["gs232a", "gs232b", "easycomm2", "easycomm3", "prosistel-combi", "rc2800", "rot2prog"]
)
def test_an_az_el_box_turning_the_azimuth_keeps_its_own_elevation_where_it_is(model: str) -> None:
    """protocols/axes.py rule 1: its codec writes an elevation in every target; it is the one
    the box reported, never the horizon (``W200 000``: the box's elevation rotor driven to 0
    at every azimuth move)."""
    boxes = {Axis.AZIMUTH: {"start_el_deg": 45.0}, Axis.ELEVATION: FAST[Axis.AZIMUTH]}
    with VirtualComposite(model, "rt21", emulators=boxes) as v:
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(200.0, 10.0))
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > 5, 200, "idle")
        assert v.status.bearing_deg is not None and abs(v.status.bearing_deg - 200.0) <= 1.0
        assert v.az.truth().el_deg == 45.0
        assert v.status.elevation_deg == 10.0


def test_a_rot2prog_at_a_quarter_degree_keeps_its_other_axis_on_its_step() -> None:
    """protocols/axes.py rules 1 and 2 with spid.py rule 1: a Rot2Prog set to 0.25 degrees
    reads 44.25 as 44.2, and a target snaps down to its grid: sent back as read, its elevation
    (the azimuth box's) or its azimuth (the elevation box's) went one step down, 44.0, at the
    first move of the other axis (a surprise move of a rotor nobody asked to turn)."""
    boxes = {
        Axis.AZIMUTH: {"resolution_ppd": 4, "start_el_deg": 44.25},
        Axis.ELEVATION: {"resolution_ppd": 4, "start_az_deg": 120.75},
    }
    with VirtualComposite("rot2prog", "rot2prog", emulators=boxes) as v:
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(200.0, 10.0))
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > 5, 400, "idle")
        assert (v.az.truth().az_deg % 360, v.el.truth().el_deg) == (200.0, 10.0)
        assert v.az.truth().el_deg == 44.25  # the azimuth box's elevation never turned
        assert v.el.truth().az_deg == 120.75  # the elevation box's azimuth never turned


def test_an_az_el_box_turning_the_azimuth_whose_elevation_reads_below_zero_still_turns() -> None:
    """protocols/axes.py rule 1: the elevation sent back is within the box's own range (an
    Easycomm box reads -0.5 and writes nothing below 0: the target raised, and the azimuth
    box's port was closed as for a bug, at every move)."""
    boxes = {Axis.AZIMUTH: {}, Axis.ELEVATION: FAST[Axis.AZIMUTH]}
    with VirtualComposite("easycomm2", "rt21", emulators=boxes) as v:
        line = bytearray()

        def below_zero(data: bytes, now: float) -> bytes:  # (the box sends byte by byte)
            line.extend(data)
            if not line.endswith(b"\n"):
                return b""
            whole = bytes(line).replace(b"EL0.0", b"EL-0.5")
            line.clear()
            return whole

        v.az.to_host = below_zero
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(200.0, 10.0))
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > 5, 200, "idle")
        assert v.status.bearing_deg is not None and abs(v.status.bearing_deg - 200.0) <= 1.0
        assert [w for w in v.az.sent() if b"." in w] == [b"AZ200.0 EL0.0\n"]


def test_a_glitched_reading_of_the_elevation_box_never_becomes_its_azimuth() -> None:
    """The azimuth an az/el box used for its elevation is sent back (protocols/axes.py rule 2)
    is one the session took as a reading: a well-formed glitch just before the real reply is
    no reading (link.py rule 9), and a target sent before the box is asked again must not carry
    it, or the box's own azimuth rotor turns to 359."""
    boxes = {**FAST, Axis.ELEVATION: {**FAST[Axis.ELEVATION], "start_az_deg": 100.0}}
    with VirtualComposite("rt21", "gs232b", emulators=boxes) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(5.0)
        glitched = v.el.glitch_once(b"A", b"AZ=359  EL=000\r\n")
        v.run_until(lambda h: glitched, 10, "the glitch reaches the bridge")
        t = v.now
        v.aim(Target(200.0, 30.0))  # while the glitched exchange is not over yet
        v.run_for(20.0)
        sent = [w for w in v.el.sent(since=t) if w.startswith(b"W")]
        assert sent and all(w.startswith(b"W100 ") for w in sent), sent
        assert v.el.truth().az_deg == 100.0  # its own azimuth never turned
        assert abs(v.el.truth().el_deg - 30.0) <= 1.0


# -- a feature's own command (session/parts.py rule 5) -----------------------------------------
AIMED: list[tuple[str, float]] = []  # (the command's name, its value) per call of the part


def _aim(s: RotatorSession, cmd: FeatureCommand, now: float) -> Proposal | None:
    """``aim`` turns the azimuth, ``aim2`` both axes (to 30° up), ``label`` moves nothing,
    ``halt`` stops the turn under way."""
    assert isinstance(cmd.value, float)
    AIMED.append((cmd.name, cmd.value))
    if cmd.name == "label":
        return None
    if cmd.name == "halt":  # as following's halt: the turn under way stops
        return Proposal(halt=True)
    el = 30.0 if cmd.name == "aim2" else None
    try:  # judged as a part judges its own (parts.py rule 2)
        target = s.cfg.aim.judge(Target(cmd.value, el), s.status.raw_bearing_deg)
    except Refused as exc:
        return Proposal(error=Report(ErrorKind.REFUSED, exc.message, describe_command(cmd)))
    return Proposal(target=target)


AIM_PART = Part[RotatorSession](
    "aimer",
    Wake.STEP,
    True,
    lambda s: False,
    lambda s, scene: None,
    lambda s, now: None,
    command=_aim,
)
AIMER = Feature("aimer", "docs/architecture.md", "aims on its own command", part=AIM_PART)


@pytest.fixture
def aimer(monkeypatch: pytest.MonkeyPatch) -> Iterator[VirtualComposite]:
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, AIMER))
    AIMED.clear()
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(2.0)
        yield v


def errors(v: VirtualComposite, kind: str | None = None) -> list[Report]:
    """Every error event either box handed out (each goes to the rotator's R/error)."""
    return [*v.az.errors(kind), *v.el.errors(kind)]


def _command(v: VirtualComposite, name: str, value: float, moves: bool = True) -> float:
    t = v.now
    v.mailbox.put_feature(FeatureCommand("aimer", name, value, moves=moves))
    v._take()
    return t


def test_a_features_command_acts_once_and_turns_the_azimuth_box_alone(
    aimer: VirtualComposite,
) -> None:
    """One command to the rotator is one call of its part, in the box whose status (the
    feature's block in it) is the rotator's; the elevation box is sent nothing for it."""
    v = aimer
    t = _command(v, "aim", 200.0)
    v.run_until(lambda h: abs(h.az.truth().az_deg - 200.0) <= 1.0, 60, "the azimuth at 200")
    v.run_for(5.0)
    assert AIMED == [("aim", 200.0)]
    assert v.el.sent(since=t) == [] or all(w.startswith(b"C2") for w in v.el.sent(since=t))
    assert v.el.truth().el_deg == 0.0 and errors(v) == []
    _command(v, "label", 1.0, moves=False)
    assert AIMED == [("aim", 200.0), ("label", 1.0)]


def test_a_features_command_that_aims_both_axes_is_refused_once_and_moves_nothing(
    aimer: VirtualComposite,
) -> None:
    """Its part runs in the azimuth box, which cannot carry an elevation: refused on the error
    topic, said once, and neither box turns (not the elevation alone)."""
    v = aimer
    t = _command(v, "aim2", 200.0)
    v.run_for(20.0)
    assert AIMED == [("aim2", 200.0)]
    refused = errors(v, "refused")
    assert len(refused) == 1 and refused[0].command == "aimer aim2 200", refused
    assert v.az.frames("move", since=t) == [] and v.el.frames("move", since=t) == []
    assert (v.az.truth().az_deg, v.el.truth().el_deg) == (0.0, 0.0)


def test_a_features_halt_stops_both_boxes(aimer: VirtualComposite) -> None:
    """Both boxes turn; the feature's own command halts: its part runs in the azimuth box, and
    the elevation box is stopped too, in the same serve, not left to turn to its target."""
    v = aimer
    v.aim(Target(300.0, 80.0))
    v.run_until(lambda h: h.el.truth().is_moving and h.az.truth().is_moving, 20, "both turn")
    v.run_for(1.0)
    t = _command(v, "halt", 0.0)
    assert AIMED == [("halt", 0.0)]
    v.run_for(0.5)
    assert v.az.frames("stop", since=t) and v.el.frames("stop", since=t)
    v.run_for(5.0)
    assert not v.az.truth().is_moving and not v.el.truth().is_moving
    assert v.el.truth().el_deg < 60.0  # stopped on its way, not at its target


def test_a_features_command_beside_a_target_stops_no_box_it_did_not_halt(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """An azimuth target (a turning Rotor-EZ stops first, then turns anew) and a feature's
    command that halts nothing, in one batch: the elevation box turns on to its target, with
    no stop (one stop asked of the azimuth box is no halt of the feature's)."""
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, AIMER))
    AIMED.clear()
    el_fast = {Axis.ELEVATION: FAST[Axis.ELEVATION]}
    with VirtualComposite("rotorez", "gs232b", emulators=el_fast) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(2.0)
        v.aim(Target(300.0, 80.0))
        v.run_until(lambda h: h.el.truth().is_moving and h.az.truth().is_moving, 20, "both turn")
        v.run_for(1.0)
        t = v.now
        v.mailbox.put(v.cfg.aim.judge(Target(200.0, None), v.status.raw_bearing_deg))
        v.mailbox.put_feature(FeatureCommand("aimer", "label", 1.0, moves=False))
        v._take()
        v.run_until(lambda h: abs(h.el.truth().el_deg - 80.0) <= 1.0, 60, "the elevation at 80")
        assert v.el.frames("stop", since=t) == []
        assert AIMED == [("label", 1.0)]


ARMED: dict[int, float] = {}  # a halter's session -> when it halts


def _arm(s: RotatorSession, cmd: FeatureCommand, now: float) -> Proposal | None:
    ARMED[id(s)] = now + 1.0
    return None


def _halt_when_due(s: RotatorSession, scene: Scene) -> Proposal | None:
    at = ARMED.get(id(s))
    if at is None or scene.now < at:
        return None
    del ARMED[id(s)]
    return Proposal(halt=True)


HALTER = Feature(
    "halter",
    "docs/architecture.md",
    "halts a second after its command",
    part=Part[RotatorSession](
        "halter",
        Wake.STEP,
        True,
        lambda s: id(s) in ARMED,
        _halt_when_due,
        lambda s, now: None,
        wakeup=lambda s, now: ARMED.get(id(s)),
        command=_arm,
    ),
)


def test_a_halt_a_features_part_proposes_later_stops_the_elevation_box_too(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The part runs in the azimuth box alone (rule 6) and halts a second after its command,
    in a step of its own: the elevation box is stopped in that serve, not left to turn on."""
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, HALTER))
    ARMED.clear()
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(2.0)
        v.aim(Target(300.0, 80.0))
        v.run_until(lambda h: h.el.truth().is_moving and h.az.truth().is_moving, 20, "both turn")
        t = v.now
        v.mailbox.put_feature(FeatureCommand("halter", "arm", 0.0, moves=False))
        v._take()
        v.run_for(3.0)
        az, el = v.az.frames("stop", since=t), v.el.frames("stop", since=t)
        assert az and el and abs(el[0].time_s - az[0].time_s) < 0.05
        v.run_for(5.0)
        assert not v.el.truth().is_moving and v.el.truth().el_deg < 60.0


def test_a_transmission_during_a_following_turn_holds_following_in_both_boxes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Following runs in both boxes and halts each on its own when a transmission begins
    (follow.py rule 3): that halt is no feature command's, so the elevation box is handed no
    stop of the azimuth box's, and following is held, not ended, in both (rule 6)."""
    worker, axes = app.worker_config, app.axis_configs
    monkeypatch.setattr(
        virtual_composite, "worker_config", lambda r, sky=None, follow=None: worker(r, sky, STATION)
    )
    monkeypatch.setattr(
        virtual_composite, "axis_configs", lambda r, sky=None, follow=None: axes(r, sky, STATION)
    )
    with VirtualComposite("rot2prog", "gs232b") as v:
        v.run_until(online, 20, "both boxes answer")
        v.run_for(2.0)
        v.mailbox.put_follow(Follow(True, False))
        v._take()
        v.mailbox.put_heard(Heard("JA1ABC", "PM95", False))
        v._take()
        v.run_for(1.5)
        assert v.az.truth().is_moving
        v.mailbox.put_heard(Heard("JA1ABC", "PM95", True))  # a transmission begins
        v._take()
        v.run_for(3.0)
        assert not v.az.truth().is_moving
        assert v.az.status.following is not None and v.el.status.following is not None
        assert v.status.following is not None


def test_the_composite_worker_says_which_stops_its_status_shows() -> None:
    """mailbox.py rule 10, as a single worker's session says it: once both boxes decided on a
    batch and their statuses were handed on, its halt count is the merged status's (a nudge
    judged before that is made from the bearing, not from the target the stop dropped)."""
    rotator = RotatorSettings.model_validate(
        {
            "id": "v",
            "azimuth": {"model": "rt21", "port": "/dev/ttyAZ"},
            "elevation": {"model": "gs232b", "port": "/dev/ttyEL"},
        }
    )
    axes = app.axis_configs(rotator)
    assert axes is not None

    def unplugged(path: str, spec: object, baud: int) -> serial.Serial:
        raise PortError(f"{path}: no such port")

    box = Mailbox()
    worker = CompositeWorker(
        app.worker_config(rotator),
        axes,
        box,
        lambda s: None,
        lambda e: None,
        port_opener=unplugged,
    )
    worker.begin(0.0, lambda: None)
    box.put(Stop())
    box.put(Stop())
    assert (box.epoch, worker.halts_applied) == (2, 0)
    worker.serve(0.1, {box.fileno()})
    assert worker.halts_applied == 2
    assert all(b.session.controller.stops.owed for b in worker.boxes.values())  # both boxes
    box.close()


@pytest.mark.parametrize("axis", [Axis.AZIMUTH, Axis.ELEVATION])
def test_a_box_whose_unused_axis_never_reads_the_same_twice_still_turns(axis: Axis) -> None:
    """protocols/axes.py rule 5: a box's unused axis counts once said twice after a connect,
    or, when none of KEEP_FIRST_READINGS agree (a worn or floating pot: 100, 103, 100...),
    as the latest reads (a review: no target ever went, and the box was asked about 37 times a
    second)."""
    gs232b = {"az_speed_deg_s": 6.0, "start_az_deg": 100.0, "start_el_deg": 10.0}
    boxes = {axis: gs232b, (Axis.ELEVATION if axis is Axis.AZIMUTH else Axis.AZIMUTH): {}}
    models = ("gs232b", "rt21") if axis is Axis.AZIMUTH else ("rt21", "gs232b")
    with VirtualComposite(*models, emulators=boxes) as v:
        box = v.boxes[axis]
        device, jitter = box.device, itertools.cycle([0, 3])
        reading = device._reading

        def jittering(text: str) -> bytes:  # the unused axis's digits: 100/103 or 010/013
            out = reading(text)
            unused = out[:6] if axis is Axis.ELEVATION else out[-3:]
            shaken = b"%03d" % (int(unused[-3:]) + next(jitter))
            return out[:3] + shaken + out[6:] if axis is Axis.ELEVATION else out[:-3] + shaken

        device._reading = jittering
        v.run_until(online, 10, "both boxes answer")
        t = v.now
        v.aim(Target(200.0, 30.0))
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > t + 5, 200, "idle")
        bearing, elevation = v.status.bearing_deg, v.status.elevation_deg
        assert bearing is not None and abs(bearing - 200.0) <= 1
        assert elevation is not None and abs(elevation - 30.0) <= 1
        assert len(box.sent(since=t)) < 400  # (polled as ever, not without end)


@pytest.mark.parametrize("how", ["silent", "unplugged"])
def test_a_box_gone_silent_mid_turn_stops_the_other_boxs_turn_too(how: str) -> None:
    """One GS-232B az/el box that goes silent mid-turn is stopped on both axes (d35d250); the
    same antenna on two boxes had only the silent box stopped, the azimuth box running on to
    the target the bridge dropped, while the rotator showed offline (composite.py rule 8). An
    elevation box unplugged mid-turn (nothing can be written to it) stops the azimuth's too."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(200.0, 60.0))
        v.run_for(2.0)
        t = v.now
        if how == "silent":
            v.el.set_silent(True)
        else:
            v.el.link_down()
        v.run_until(lambda c: not c.status.available, 10, "offline")
        if how == "silent":
            assert b"S\r" in v.el.sent(since=t)  # (the silent box: its offline stop)
        v.run_for(3.0)
        assert not v.az.truth().is_moving
        assert v.az.truth().az_deg < 100.0  # (stopped short, not on at 200)


def test_an_event_both_boxes_say_is_said_once_and_a_command_sent_again_is_said_again() -> None:
    """composite.py rule 9, on the composition alone: twins are matched one for one, within
    TWIN_S; an event one box alone says (its port, its axis) is always said."""
    c = Composition("sky")
    az, el = Axis.AZIMUTH, Axis.ELEVATION

    def refused(t: float, what: str = "track X") -> ErrorEvent:
        return ErrorEvent(ErrorKind.REFUSED, "no satellite 'X'", what, t)

    # the same command twice: each box's pair, interleaved, says it twice in all
    said = [c.said(az, refused(0.0)), c.said(az, refused(0.5)), c.said(el, refused(0.1))]
    said += [c.said(el, refused(0.6))]
    assert said == [True, True, False, False]
    assert c.said(el, ErrorEvent(ErrorKind.SERIAL, "port /dev/b gone", None, 1.0))
    assert c.said(az, ErrorEvent(ErrorKind.SERIAL, "port /dev/a gone", None, 1.0))
    assert c.said(az, refused(2.0, "track Y"))  # another command's words: no twin
    assert c.said(el, refused(2.0 + TWIN_S))  # one box's, long after: its own event
    assert c.said(az, refused(2.0 + TWIN_S + 0.1)) is False  # ... whose twin this is


def test_a_box_that_restarted_mid_turn_abandons_the_rotators_turn_in_both_boxes() -> None:
    """A Rotor-EZ azimuth box power-cycled mid-turn (its 0xE0 byte: controller.py rule 12)
    abandons its turn and says it was not resumed; the elevation box carried on to the user's
    elevation, the antenna left half moved under that word (a review). The rotator's turn is
    abandoned whole (composite.py rule 8), said once."""
    emulators = {Axis.ELEVATION: FAST[Axis.ELEVATION]}
    with VirtualComposite("rotorez", "gs232b", emulators=emulators) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(1.0)
        v.aim(Target(300.0, 80.0))
        v.run_until(lambda c: c.az.truth().az_deg > 30, 60, "azimuth turning")
        t = v.now
        v.az.power_cycle()
        v.run_for(60.0)
        elevation = v.el.truth().el_deg
        assert elevation < 60.0, elevation  # observed: 80, the elevation box arrived
        assert not v.el.truth().is_moving
        said = [e.message for box in (v.az, v.el) for e in box.errors(since=t)]
        restarts = [m for m in said if m.startswith("the controller restarted mid-turn")]
        assert len(restarts) == 1 and len(said) == 1, said
        status = v.status
        assert status.target_az_deg is None and status.target_el_deg is None
        assert status.state is MotionState.IDLE


@pytest.mark.parametrize("fault", ["jam", "power_cycle"])
def test_a_box_that_stalls_mid_turn_abandons_the_rotators_turn_in_both_boxes(fault: str) -> None:
    """composite.py rule 8 (an attack pass): an RT-21 azimuth box whose rotor jams mid-turn,
    or that is power-cycled (its readings a stall's: controller.py rule 12), is said stalled,
    its target dropped; the elevation box turned on alone to the dropped target's 80."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(1.0)
        v.aim(Target(300.0, 80.0))
        v.run_until(lambda c: c.az.truth().az_deg > 30, 60, "azimuth turning")
        t = v.now
        getattr(v.az, fault)()
        v.run_until(lambda c: bool(c.az.errors(since=t)), 60, "the stall said")
        at_stall = v.el.truth().el_deg
        v.run_for(60.0)
        assert v.el.truth().el_deg < at_stall + 2.0, (at_stall, v.el.truth())  # observed: 80
        assert not v.el.truth().is_moving
        said = [e.message for box in (v.az, v.el) for e in box.errors(since=t)]
        assert len(said) == 1 and said[0].startswith("rotor stalled at"), said
        status = v.status
        assert status.target_az_deg is None and status.target_el_deg is None
        assert status.state is not MotionState.MOVING


def test_both_boxes_jammed_mid_turn_each_say_their_stall() -> None:
    """composite.py rule 8: the azimuth box's stall abandons the elevation's turn, but an
    elevation rotor that stands too (ice on both) is left to its own stall, said and counted
    by rotor health, not abandoned unsaid."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(1.0)
        v.aim(Target(300.0, 80.0))
        v.run_until(lambda c: c.el.truth().el_deg > 5, 60, "both turning")
        t = v.now
        v.az.jam()
        v.el.jam()
        v.run_for(60.0)
        stalls = sorted(
            e.message.split(" (")[0] for box in (v.az, v.el) for e in box.errors(since=t)
        )
        assert len(stalls) == 2 and all(m.startswith("rotor stalled at") for m in stalls), stalls
        assert "elevation" in stalls[1], stalls


@pytest.mark.parametrize("between", ["wind", "track off"])
def test_a_standing_box_is_abandoned_when_it_moves_after_a_wind_reading_came_between(
    between: str,
) -> None:
    """composite.py rule 8 (two reviews): the azimuth box stalls while the elevation box stands
    (jammed too, not yet said); a wind reading comes, or tracking is switched off; the
    elevation's rotor comes free. Neither asks motion of its own: the elevation is abandoned
    as it moves, not left to turn on to the 80 of the target said dropped."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(1.0)
        v.aim(Target(300.0, 80.0))
        v.run_until(lambda c: c.el.truth().el_deg > 5, 60, "both turning")
        t = v.now
        v.az.jam()
        v.run_for(6.0)
        v.el.jam()
        v.run_until(lambda c: bool(c.az.errors(since=t)), 60, "the azimuth's stall said")
        if between == "wind":
            v.mailbox.put_wind(12.0)
            v._take()
        else:
            v.track(None)
        v.el.unjam()
        v.run_for(60.0)
        assert v.el.truth().el_deg < 50.0, v.el.truth()  # observed: on to 80
        assert v.status.target_el_deg is None


def test_a_satel_box_slewing_when_the_other_box_stalls_is_stopped() -> None:
    """composite.py rule 8 (a review): a SatEL says nothing while it slews, so its rotor looked
    as if it stood (no movement since its target went out) and was left to a stall of its own
    that never comes; it slewed on to the 60 of the target the azimuth box's stall dropped."""
    emulators = {Axis.AZIMUTH: {"az_speed_deg_s": 6.0}}
    with VirtualComposite("gs232b-az", "satel", emulators=emulators) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(1.0)
        v.aim(Target(300.0, 60.0))
        v.run_for(3.0)
        t = v.now
        v.az.jam()
        v.run_until(lambda c: bool(c.az.errors(since=t)), 60, "the azimuth's stall said")
        at_stall = v.el.truth().el_deg
        v.run_for(60.0)
        assert v.el.truth().el_deg < at_stall + 5.0, (at_stall, v.el.truth())  # observed: 60
        assert v.status.target_el_deg is None


def test_a_satel_box_restarted_mid_slew_abandons_the_rotators_turn_in_both_boxes() -> None:
    """A SatEL elevation box power-cycled mid-slew: its clock gone back at the first reading
    after the lost report tells the restart (controller.py rule 14), its turn is not resumed;
    the azimuth box turned on to the user's azimuth under that word, the antenna left half
    moved (a cold review), where a restart told by a power-on byte abandons both (rule 8)."""
    emulators = {Axis.AZIMUTH: {"az_speed_deg_s": 1.0}}
    with VirtualComposite("gs232b-az", "satel", emulators=emulators) as v:
        v.run_until(online, 30, "both boxes answer")
        v.run_for(1.0)
        v.aim(Target(300.0, 60.0))
        v.run_for(10.0)
        t = v.now
        v.el.power_cycle()
        v.run_until(
            lambda c: any("restarted mid-turn" in e.message for e in c.el.errors(since=t)),
            200,
            "the restart said",
        )
        v.run_for(10.0)
        assert not v.az.truth().is_moving
        assert v.az.truth().az_deg < 250.0, v.az.truth()  # stopped short, not on at 300
        said = [e.message for box in (v.az, v.el) for e in box.errors(since=t)]
        assert len([m for m in said if "restarted mid-turn" in m]) == 1, said
        assert v.status.target_az_deg is None and v.status.target_el_deg is None


def test_a_box_that_says_it_gave_its_turn_up_abandons_the_rotators_turn_in_both_boxes() -> None:
    """A Prosistel D azimuth box power-cycled mid-turn says its motor is braked (controller.py
    rule 12): its turn is dropped at once, and the elevation box's with it (composite.py rule
    8), said once, not the elevation turned on to the user's elevation under that word."""
    emulators = {Axis.ELEVATION: FAST[Axis.ELEVATION]}
    with VirtualComposite("prosistel", "gs232b", emulators=emulators) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(1.0)
        v.aim(Target(300.0, 80.0))
        v.run_until(lambda c: c.az.truth().az_deg > 30, 60, "azimuth turning")
        t = v.now
        v.az.power_cycle()
        v.run_for(60.0)
        elevation = v.el.truth().el_deg
        assert elevation < 60.0, elevation
        assert not v.el.truth().is_moving
        said = [e.message for box in (v.az, v.el) for e in box.errors(since=t)]
        gave_up = [m for m in said if m.startswith("the controller stopped turning short")]
        assert len(gave_up) == 1 and len(said) == 1, said
        status = v.status
        assert status.target_az_deg is None and status.target_el_deg is None
        assert status.state is MotionState.IDLE


def test_both_boxes_refusing_the_target_are_said_each_the_elevations_by_its_elevation() -> None:
    """stops.py rule 4 and composite.py rule 9: both GS-232 boxes answer a target with their
    refusal (``?>``), the azimuth box resting at north. The elevation box's refusal named its
    own azimuth, which it never turns ('its refusal at 0°'), word for word the azimuth box's,
    so rule 9 took the two for one event and the elevation box's was never said."""
    with VirtualComposite("gs232b-az", "gs232b") as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(1.0)
        # (three digits beyond each box's range, and so again: one refusal is tried once more)
        v.az.garble_writes(b"M200\r", b"M999\r", count=2)
        v.el.garble_writes(b"W000 030\r", b"W000 999\r", count=2)
        t = v.now
        v.aim(Target(200.0, 30.0))
        v.run_for(5.0)
        told = sorted(
            (when, axis, r)
            for axis, box in v.boxes.items()
            for when, r in box.events
            if when >= t and r.kind == ErrorKind.REFUSED
        )
        rule_9 = Composition("v")  # (as CompositeWorker hands on the boxes' events)
        said = [
            r.message
            for when, axis, r in told
            if rule_9.said(axis, ErrorEvent(r.kind, r.message, r.command, when))
        ]
        at = sorted(m.split("): ")[0] for m in said)
        assert at == [
            "the controller refused the target (it answered with its refusal at 0°",
            "the controller refused the target (it answered with its refusal at elevation 0°",
        ], said


def test_an_elevation_box_freed_after_its_stall_names_its_elevation_turning() -> None:
    """stops.py rule 4: the elevation box stalled (iced), its stall's stop lost on the line;
    freed, it turns on to its old elevation and is stopped once more, said. It said 'rotor
    turning at 0°', its own azimuth, which it never turns, word for word what the azimuth box
    at north says (composite.py rule 9 then says the two once)."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(1.0)
        v.el.jam()
        v.el.drop_writes(b"S\r")  # (the stall's stop, lost)
        v.aim(Target(20.0, 30.0))
        v.run_until(lambda c: c.el.errors(ErrorKind.STALLED), 60, "the elevation's stall")
        t = v.now
        v.el.unjam()
        v.run_until(lambda c: c.el.errors(ErrorKind.STOP, since=t), 10, "turning on: stopped")
        [turning] = [r.message for r in v.el.errors(ErrorKind.STOP, since=t)]
        assert turning.startswith("rotor turning at elevation "), turning
        v.run_until(lambda c: not c.el.truth().is_moving, 10, "stopped once more")
        assert v.el.truth().el_deg < 25.0


def _lost_azimuth_elevation_turning(v: VirtualComposite) -> float:
    """G4XYZ's 300/40: the RT-21 azimuth box's frame lost on its line, the GS-232B elevation
    box's half sent and turning. The time it was sent."""
    v.run_until(online, 10, "both boxes answer")
    v.run_for(3.0)
    v.az.drop_writes(b"AP1300.0\r;")  # the azimuth's frame lost on the line
    t = v.now
    v.aim(Target(300.0, 40.0, origin=Origin(Source.MQTT, "G4XYZ")))
    v.run_until(lambda h: h.el.truth().is_moving, 5, "the elevation turning")
    return t


def _the_drop_said(v: VirtualComposite, since: float) -> str | None:
    """composite.py rule 9: the command the azimuth box's one drop is said with on R/error."""
    [drop] = v.az.errors("refused", since=since)
    event = ErrorEvent(drop.kind, drop.message, drop.command, v.wall())
    return v.composition.whole(Axis.AZIMUTH, event).command


def test_a_storm_that_drops_the_azimuths_try_more_drops_the_elevations_half_too() -> None:
    """composite.py rules 8 and 9, wind.py rule 1, controller.py rule 11: a storm known only
    from a replay begins before the reading that would send 300/40's lost azimuth once more.
    The azimuth box drops its try more (the storm refuses motion), but the elevation box
    turned on to 40 for the target the storm had dropped, the antenna left half moved, and
    R/error named 'target az 300' alone (a cold review); a waiting azimuth's drop stops the
    elevation and names the whole target."""
    wind = {"wind_topic": "weather/wind", "wind_park_above": 60, "wind_park_az_deg": 180}
    with VirtualComposite("rt21", "gs232b", settings=wind, emulators=FAST) as v:
        t = _lost_azimuth_elevation_turning(v)
        v.mailbox.put_wind(90.0, replayed=True)
        v._take()
        assert v.status.wind is not None and v.status.wind.storm
        v.run_for(30.0)
        assert [d for d in v.az.sent(since=t) if d.startswith(b"AP1")] == [b"AP1300.0\r;"]
        assert v.el.truth().el_deg < 30.0, v.el.truth()  # observed: on to 40
        assert _the_drop_said(v, t) == "target az 300 el 40"  # observed: 'target az 300'


def test_a_claim_that_takes_the_azimuths_try_more_names_the_whole_target() -> None:
    """composite.py rule 9, session.py rule 23: DL1ABC claims the lease before the reading that
    would send G4XYZ's lost azimuth once more. The azimuth box takes the try more and the
    elevation box is stopped (rule 8), but R/error's 'target not sent again' named 'target az
    300' alone, where the user lost 300/40 (a cold review)."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        t = _lost_azimuth_elevation_turning(v)
        v.mailbox.put_control(Control("DL1ABC", v.wall() + 1800))
        v._take()
        v.run_for(30.0)
        assert [d for d in v.az.sent(since=t) if d.startswith(b"AP1")] == [b"AP1300.0\r;"]
        assert v.el.truth().el_deg < 30.0, v.el.truth()
        assert _the_drop_said(v, t) == "target az 300 el 40"  # observed: 'target az 300'


def test_a_claim_that_drops_one_senders_azimuth_leaves_the_holders_own_elevation() -> None:
    """composite.py rule 8, session.py rule 23: G4XYZ's 300/40 mid-turn: the Rotor-EZ azimuth
    box holds 300 for its brake, the GS-232B elevation box turns to 40. DL1ABC sends an
    elevation of 10 alone, then claims the lease: G4XYZ's azimuth is dropped, and the other box
    dropped its half of the rotator's last target, DL1ABC's own 10, unsaid, so the elevation
    went on to G4XYZ's 40, half of the target the claim refused (a cold review). The other
    box drops only the half of the same sender's target."""
    emulators = {
        Axis.AZIMUTH: {"speed_deg_s": 6.0, "jitter_deg": 0},
        Axis.ELEVATION: {**FAST[Axis.ELEVATION], "el_speed_deg_s": 2.0},
    }
    g4xyz, dl1abc = Origin(Source.MQTT, "G4XYZ"), Origin(Source.MQTT, "DL1ABC")
    with VirtualComposite("rotorez", "gs232b", emulators=emulators) as v:
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(120.0, 20.0, origin=g4xyz))
        v.run_until(lambda h: h.az.truth().az_deg > 30, 30, "turning")
        v.aim(Target(300.0, 40.0, origin=g4xyz))  # (a stop, and 300 waits for the brake)
        v.run_for(0.3)
        assert v.az.truth().in_brake_delay and v.el.truth().is_moving
        t = v.now
        v.aim(Target(None, 10.0, origin=dl1abc))
        v.run_for(0.3)
        v.mailbox.put_control(Control("DL1ABC", v.wall() + 1800))
        v._take()
        v.run_until(lambda h: not h.el.truth().is_moving, 60, "the elevation at rest")
        v.run_for(5.0)
        assert v.el.truth().el_deg == pytest.approx(10.0, abs=1.0)  # observed: 40
        assert b"W000 010\r" in v.el.sent(since=t)
        assert [f for f in v.az.sent(since=t) if f.startswith(b"AP1")] == []
        said = [(r.command, r.origin) for box in (v.az, v.el) for r in box.errors(since=t)]
        assert said == [("target az 300", g4xyz)]


def test_a_claim_that_drops_an_azimuth_sent_alone_drops_its_senders_elevation_too() -> None:
    """composite.py rules 8 and 9, core/model.py ``combine``: G4XYZ's 300/40 mid-turn, the
    Rotor-EZ azimuth box holds 300 for its brake and the GS-232B elevation box turns to 40;
    G4XYZ then sends an azimuth of 310 alone, taken with that 40 (one sender's two halves
    combine). DL1ABC's claim drops 310, but the elevation turned on to 40, the antenna left
    half moved for a target the lease refused, and R/error named 'target az 310' alone (a
    cold review): the rotator's target was the last one's halves, and 310 has none there."""
    emulators = {
        Axis.AZIMUTH: {"speed_deg_s": 6.0, "jitter_deg": 0},
        Axis.ELEVATION: {**FAST[Axis.ELEVATION], "el_speed_deg_s": 2.0},
    }
    g4xyz = Origin(Source.MQTT, "G4XYZ")
    with VirtualComposite("rotorez", "gs232b", emulators=emulators) as v:
        v.run_until(online, 10, "both boxes answer")
        v.aim(Target(120.0, 20.0, origin=g4xyz))
        v.run_until(lambda h: h.az.truth().az_deg > 30, 30, "turning")
        v.aim(Target(300.0, 40.0, origin=g4xyz))  # (a stop, and 300 waits for the brake)
        v.run_for(0.3)
        t = v.now
        v.aim(Target(310.0, None, origin=g4xyz))
        v.run_for(0.3)
        assert v.az.truth().in_brake_delay and v.el.truth().is_moving
        v.mailbox.put_control(Control("DL1ABC", v.wall() + 1800))
        v._take()
        v.run_until(lambda h: not h.el.truth().is_moving, 60, "the elevation at rest")
        v.run_for(5.0)
        assert v.el.truth().el_deg < 30.0, v.el.truth()  # observed: on to 40
        assert [f for f in v.az.sent(since=t) if f.startswith(b"AP1")] == []
        assert _the_drop_said(v, t) == "target az 310 el 40"  # observed: 'target az 310'


def test_a_claim_that_drops_the_azimuth_drops_a_satel_elevations_half_put_back_too() -> None:
    """composite.py rule 8, slew.py rule 4, session.py rule 23: G4XYZ's elevation 40 goes to
    the SatEL elevation box, slower than configured, then their azimuth 300 alone (taken with
    40: one sender's two halves), which the Rotor-EZ azimuth box holds for its brake. The
    SatEL's report is late: it is stopped and 40 put back. DL1ABC's claim drops the azimuth's
    300, but the put-back 40 was a new target the elevation box's ``forsake`` did not know
    for the rotator's half (a cold review): it went out and the elevation turned on to 40,
    the antenna left half moved for a target the lease refused."""
    g4xyz = Origin(Source.MQTT, "G4XYZ")
    emulators = {
        Axis.AZIMUTH: {"speed_deg_s": 6.0, "jitter_deg": 0},
        Axis.ELEVATION: {"el_speed_deg_s": 3.0},  # (the bridge is told 20: its report late)
    }
    settings = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 20.0}
    with VirtualComposite("rotorez", "satel", settings=settings, emulators=emulators) as v:
        v.run_until(online, 30, "both boxes answer")
        v.run_until(lambda h: h.status.state is MotionState.IDLE, 30, "out of its brake delay")
        v.aim(Target(120.0, None, origin=g4xyz))
        v.run_until(lambda h: h.az.truth().az_deg > 30, 30, "turning")
        t = v.now
        v.aim(Target(None, 40.0, origin=g4xyz))
        v.run_until(lambda h: h.el.truth().el_deg > 15, 30, "the elevation slewing")
        v.aim(Target(300.0, None, origin=g4xyz))  # (a stop, and 300 waits for the brake)
        v.run_until(
            lambda h: any(e.message.startswith("no report from") for e in h.el.errors(since=t)),
            30,
            "the elevation's late report: its 40 put back",
        )
        assert v.az.truth().in_brake_delay
        v.mailbox.put_control(Control("DL1ABC", v.wall() + 1800))
        v._take()
        v.run_until(lambda h: not h.el.truth().is_moving, 60, "the elevation at rest")
        v.run_for(10.0)
        assert not v.el.truth().is_moving
        assert v.el.truth().el_deg < 35.0, v.el.truth()  # observed: on to 40
        assert v.el.sent(since=t).count(b"p0 40\r\n") == 1  # observed: sent again
        assert [f for f in v.az.sent(since=t) if f.startswith(b"AP1")] == []
        assert _the_drop_said(v, t) == "target az 300 el 40"


def test_a_claim_that_takes_a_refused_azimuths_try_more_says_it_once_naming_the_whole() -> None:
    """session.py rule 23, controller.py rule 11, composite.py rule 9: G4XYZ's 300/40, the
    GS-232B azimuth box's frame garbled on its line into one it refuses (``?>``), and DL1ABC's
    claim before that refusal is read. The try more is not sent and the elevation is stopped,
    but R/error said two things: 'target not sent again' and the refusal (the try more's
    words, as if it were not tried again), where a storm that refuses the same try more says
    one (a cold review). One message, naming the whole target."""
    g4xyz = Origin(Source.MQTT, "G4XYZ")
    with VirtualComposite("gs232b-az", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        v.run_for(3.0)
        v.az.garble_writes(b"M300\r", b"M999\r")  # (three digits beyond the box's range)
        t = v.now
        v.aim(Target(300.0, 40.0, origin=g4xyz))
        v.mailbox.put_control(Control("DL1ABC", v.wall() + 1800))
        v._take()
        v.run_for(30.0)
        assert [d for d in v.az.sent(since=t) if d.startswith(b"M")] == [b"M300\r"]
        assert v.el.truth().el_deg < 30.0, v.el.truth()
        said = [
            v.composition.whole(axis, ErrorEvent(r.kind, r.message, r.command, v.wall()))
            for axis, box in v.boxes.items()
            for r in box.errors(since=t)
        ]
        assert [(e.kind, e.command) for e in said] == [("refused", "target az 300 el 40")], said
        assert said[0].message.startswith("target not sent again: DL1ABC holds the rotator")


def test_a_claim_that_drops_the_azimuth_stops_a_satel_elevations_half_sent_again() -> None:
    """composite.py rule 8, slew.py rule 4: as above, but G4XYZ's azimuth 300 alone comes once
    the SatEL's 40 was put back, and DL1ABC's claim once that 40 went out again, the azimuth's
    300 still held for its brake. The put back, a new target, was neither kept as the
    sender's elevation with 300 nor known for the rotator's half when the claim dropped 300:
    the elevation slewed on to 40 alone."""
    g4xyz = Origin(Source.MQTT, "G4XYZ")
    emulators = {
        Axis.AZIMUTH: {"speed_deg_s": 6.0, "jitter_deg": 0},
        Axis.ELEVATION: {"el_speed_deg_s": 3.0},  # (the bridge is told 20: its report late)
    }
    settings = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 20.0}
    with VirtualComposite("rotorez", "satel", settings=settings, emulators=emulators) as v:
        v.run_until(online, 30, "both boxes answer")
        v.run_until(lambda h: h.status.state is MotionState.IDLE, 30, "out of its brake delay")
        v.aim(Target(120.0, None, origin=g4xyz))
        v.run_until(lambda h: h.az.truth().az_deg > 30, 30, "turning")
        t = v.now
        v.aim(Target(None, 40.0, origin=g4xyz))
        v.run_until(
            lambda h: any(e.message.startswith("no report from") for e in h.el.errors(since=t)),
            30,
            "the elevation's late report: its 40 put back",
        )
        v.aim(Target(300.0, None, origin=g4xyz))  # (a stop, and 300 waits for the brake)
        v.run_until(lambda h: h.el.sent(since=t).count(b"p0 40\r\n") == 2, 30, "40 again")
        v.run_until(lambda h: h.el.truth().is_moving, 30, "the elevation slewing again")
        assert v.az.truth().in_brake_delay
        v.mailbox.put_control(Control("DL1ABC", v.wall() + 1800))
        v._take()
        v.run_until(lambda h: not h.el.truth().is_moving, 60, "the elevation at rest")
        v.run_for(10.0)
        assert not v.el.truth().is_moving
        assert v.el.truth().el_deg < 35.0, v.el.truth()  # observed: on to 40
        assert [f for f in v.az.sent(since=t) if f.startswith(b"AP1")] == []
        assert _the_drop_said(v, t) == "target az 300 el 40"  # observed: 'target az 300'


def test_a_tracking_or_following_off_ends_what_either_box_still_does() -> None:
    """runtime/audit.py rule 10: whether a tracking or following OFF changes anything is asked
    of both boxes (rule 4: one box may still track or follow while the merged status, the
    azimuth box's, shows nothing), so an OFF that ends the elevation box's tracking is never
    folded away as a halt that changed nothing."""
    rotator = RotatorSettings.model_validate(
        {
            "id": "v",
            "azimuth": {"model": "rt21", "port": "/dev/ttyAZ"},
            "elevation": {"model": "gs232b", "port": "/dev/ttyEL"},
        }
    )
    axes = app.axis_configs(rotator)
    assert axes is not None

    def unplugged(path: str, spec: object, baud: int) -> serial.Serial:
        raise PortError(f"{path}: no such port")

    box = Mailbox()
    worker = CompositeWorker(
        app.worker_config(rotator),
        axes,
        box,
        lambda s: None,
        lambda e: None,
        port_opener=unplugged,
    )
    worker.begin(0.0, lambda: None)
    assert worker.features_on == (False, False)
    worker.boxes[Axis.ELEVATION].session.tracker.start(Body.sun())  # the azimuth's ended
    assert worker.status.tracking is None and worker.features_on == (True, False)
    worker.boxes[Axis.ELEVATION].session.tracker.end("off")
    worker.boxes[Axis.ELEVATION].session.follower.start(Follow(True), 0.0)
    assert worker.status.following is None and worker.features_on == (False, True)
    box.close()


def test_the_two_boxes_audit_lines_of_one_park_of_the_bridges_own_are_one() -> None:
    """Rule 9, session.py rule 25: each box parks its own axis for the storm, and each hands
    the judge the park's audit line; the rotator's trail has one line for that park, and
    one for a later park again."""
    rotator = RotatorSettings.model_validate(
        {
            "id": "v",
            "azimuth": {"model": "rt21", "port": "/dev/ttyAZ"},
            "elevation": {"model": "gs232b", "port": "/dev/ttyEL"},
        }
    )
    axes = app.axis_configs(rotator)
    assert axes is not None
    wall = [1000.0]
    audited: list[Audit] = []
    box = Mailbox()
    worker = CompositeWorker(
        app.worker_config(rotator),
        axes,
        box,
        lambda s: None,
        lambda e: None,
        wall=lambda: wall[0],
        on_audit=audited.append,
    )
    park = Audit(Origin(Source.WIND), "park")
    worker.boxes[Axis.AZIMUTH]._do([park])  # as each box's session hands it out
    worker.boxes[Axis.ELEVATION]._do([park])
    assert audited == [park]
    wall[0] += 600.0  # a later storm's park
    worker.boxes[Axis.ELEVATION]._do([park])
    worker.boxes[Axis.AZIMUTH]._do([park])
    assert audited == [park, park]
    box.close()
