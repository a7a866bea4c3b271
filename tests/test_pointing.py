"""The one transform and judge (bridge/pointing.py): true bearings in, the controller's raw
values out, and every way of naming a target. Pure: no rotator, no clock."""

from __future__ import annotations

from dataclasses import replace

import pytest

from bridge.core import geo
from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import MotionState, RotatorStatus, Target
from bridge.pointing import Pointing, in_sector, norm360, toward, unfolded
from bridge.protocols import REGISTRY
from bridge.protocols.axes import composite_spec

EZ, SPID = REGISTRY["rotorez"], REGISTRY["rot2prog"]


def refused(call, *args) -> RefusalCode:  # noqa: ANN001
    with pytest.raises(Refused) as exc:
        call(*args)
    return exc.value.code


def test_the_offset_turns_raw_readings_into_true_bearings_and_back() -> None:
    south = Pointing.of(EZ, offset_deg=180)
    assert [south.true_of(r) for r in (10, 180, 359, 360)] == [190, 0, 179, 180]
    assert south.judge(Target(270), 10).az_deg == 90
    assert south.judge(Target(0), 10).az_deg == 180
    assert south.judge(Target(180), 10).az_deg == 0  # 0, not 360: the controller picks its way
    assert Pointing.of(EZ).judge(Target(359.6), None).az_deg == 359.6  # never -0.4
    assert south.shows_raw and not Pointing.of(EZ).shows_raw
    assert Pointing.of(SPID).shows_raw  # it can pass 360: the raw value says which side


def test_360_named_is_360_as_hamlib_sends_it() -> None:
    """Rule 2: ``rotctl -m 603 P 360 0`` sends ``W360``, the clockwise end of a GS-232's travel;
    360 folded to 0 sent a rotor at 350 the whole way back round."""
    yaesu = Pointing.of(REGISTRY["gs232b"])
    assert yaesu.judge(Target(360), 350).az_deg == 360
    assert yaesu.judge(Target(0), 350).az_deg == 0  # named 0: the other end, as Hamlib sends it
    assert Pointing.of(REGISTRY["gs232b"], (0, 359)).judge(Target(360), 350).az_deg == 0


def test_limits_stay_mechanical_and_refusals_name_both_values() -> None:
    p = Pointing.of(EZ, (20, 340), offset_deg=180)
    with pytest.raises(Refused) as exc:
        p.judge(Target(190), None)  # raw 10
    assert exc.value.code is RefusalCode.LIMITS
    assert exc.value.message == "azimuth 190 (controller 10) outside the limits 20..340"
    assert p.judge(Target(200), None).az_deg == 20
    assert refused(p.judge, Target(400), None) is RefusalCode.LIMITS  # wrapping: 0..360 only
    assert refused(p.judge, Target(float("nan")), None) is RefusalCode.LIMITS


@pytest.mark.parametrize(
    ("pointing", "target", "said"),
    [
        (Pointing.of(EZ), Target(360.00001), "azimuth 360.00001 outside 0..360"),
        (Pointing.of(EZ), Target(-0.0000001), "azimuth -1e-07 outside 0..360"),
        (Pointing.of(SPID, (0, 360)), Target(360.0000004), "azimuth 360.0000004 outside"),
        (Pointing.of(REGISTRY["gs232b"]), Target(10, 180.00001), "elevation 180.00001 out"),
    ],
)
def test_a_refusal_quotes_a_value_past_a_limit_with_the_digits_that_keep_it_past(
    pointing: Pointing, target: Target, said: str
) -> None:
    """Attack 28: six digits made 360.00001 "azimuth 360 outside 0..360" (rule 5)."""
    with pytest.raises(Refused) as exc:
        pointing.judge(target, None)
    assert exc.value.message.startswith(said), exc.value.message


@pytest.mark.parametrize(
    ("target", "current", "raw"),
    [
        (10, 350, 370),  # across north clockwise: 20 degrees, not 340 back
        (350, 10, -10),  # from 10 the way back across north is 20 degrees
        (350, -150, -10),  # on the ccw side already
        (10, None, 10),  # no reading: the one nearest the middle of -180..540 (180)
        (200, None, 200),
        (400, 10, 400),  # outside 0..360 names the side itself
        (-20, 300, -20),
    ],
)
def test_a_spid_takes_the_least_travel_inside_its_mechanical_range(
    target: float, current: float | None, raw: float
) -> None:
    assert Pointing.of(SPID).raw_for(target, current) == raw


def test_a_spid_with_an_offset_and_narrow_limits() -> None:
    p = Pointing.of(SPID, (-90, 450), offset_deg=90)
    assert p.raw_for(100, 5) == 10  # true 100 = raw 10
    assert p.raw_for(80, 5) == -10
    assert p.raw_for(80, 400) == 350  # 710 would be past the 450 stop
    assert refused(p.raw_for, 600, 5) is RefusalCode.LIMITS  # raw 510


def test_a_turn_kept_inside_an_arc_takes_the_side_that_stays_in_it() -> None:
    """Rule 9, a review: a group's limits 20..340 on a 450-degree rotor at 300; 30 went to 390,
    through the 340..20 the group keeps it out of."""
    over = Pointing.of(REGISTRY["gs232b-az-450"])
    assert over.judge(Target(30), 300).az_deg == 390  # no arc: the least travel
    kept = over.judge(Target(30, within_deg=(20, 340)), 300)
    assert (kept.az_deg, kept.true_az_deg) == (30, None)  # the side fixed: sent as judged
    assert over.judge(Target(50, within_deg=(20, 340)), 390).az_deg == 410  # past north: on
    assert refused(over.judge, Target(330, within_deg=(20, 340)), 380) is RefusalCode.LIMITS
    south = Pointing.of(EZ, offset_deg=180)  # a 360-degree rotor whose stop is at north
    assert south.judge(Target(200, within_deg=(20, 340)), 120).az_deg == 20  # (true 300)
    with pytest.raises(Refused) as exc:  # (true 300 to 30 only through north)
        south.judge(Target(30, within_deg=(20, 340)), 120)
    assert exc.value.code is RefusalCode.LIMITS
    assert exc.value.message == "azimuth 30 is not reached from 300 without turning outside 20..340"
    assert south.judge(Target(30, within_deg=(20, 340)), 180).az_deg == 210  # from true 0: in
    assert over.judge(Target(30, within_deg=(20, 340)), 19.7).az_deg == 30  # at an edge
    assert over.judge(Target(30, within_deg=(0, 360)), 300).az_deg == 390  # the whole circle
    # no reading: the way is not known (rule 9), but on a scale of true bearings that wraps
    assert refused(over.judge, Target(30, within_deg=(20, 340)), None) is RefusalCode.LIMITS
    assert refused(south.judge, Target(200, within_deg=(20, 340)), None) is RefusalCode.LIMITS
    assert Pointing.of(EZ).judge(Target(200, within_deg=(190, 340)), None).az_deg == 200
    # ... clear of north and of south, where a Hy-Gain rotor's stop is (an attack pass)
    assert (
        refused(Pointing.of(EZ).judge, Target(30, within_deg=(20, 340)), None) is RefusalCode.LIMITS
    )
    assert (
        refused(Pointing.of(EZ).judge, Target(30, within_deg=(20, 340)), 300) is RefusalCode.LIMITS
    )
    assert Pointing.of(EZ).judge(Target(200, within_deg=(20, 340)), 300).az_deg == 200
    assert over.judge(Target(30, within_deg=(0, 360)), None).true_az_deg == 30  # (rule 2)


@pytest.mark.parametrize(
    ("sector", "inside", "outside"),
    [
        ((200, 220), [200, 210, 220], [199.9, 220.1, 20]),
        ((350, 10), [350, 359.9, 0, 360, 10], [349, 11, 180]),  # clockwise across north
    ],
)
def test_keep_out_sectors_run_clockwise_edges_included(
    sector: tuple[float, float], inside: list[float], outside: list[float]
) -> None:
    assert all(in_sector(b, sector) for b in inside)
    assert not any(in_sector(b, sector) for b in outside)
    p = Pointing.of(SPID, keep_out=(sector,))
    for b in inside:
        assert refused(p.judge, Target(b, 0), None) is RefusalCode.KEEP_OUT
    assert refused(p.judge, Target(sector[0] + 360, 0), None) is RefusalCode.KEEP_OUT


def test_presets_park_and_nudges_become_true_bearings() -> None:
    p = Pointing.of(SPID, presets={"EU": (45, None), "ISS_AOS": (180, 5)}, park=(0, 0))
    assert p.preset("ISS_AOS") == (180, 5)
    assert refused(p.preset, "JA") is RefusalCode.INVALID
    assert p.parking() == (0, 0)
    assert refused(Pointing.of(EZ).parking) is RefusalCode.UNSUPPORTED

    still = RotatorStatus("t", MotionState.IDLE, bearing_deg=355, elevation_deg=10)
    assert p.nudged(still, 10, None) == (5, None)  # across north
    assert p.nudged(still, -10, 2) == (345, 12)
    turning = RotatorStatus("t", MotionState.MOVING, bearing_deg=100, target_az_deg=200)
    assert p.nudged(turning, 10, None) == (210, None)  # from where it is going
    assert refused(p.nudged, RotatorStatus("t"), 10, None) is RefusalCode.OFFLINE
    # past 360 a nudge stays on its side (review finding: +10 at 535 went 350 degrees back)
    overlap = RotatorStatus("t", MotionState.IDLE, bearing_deg=175, raw_bearing_deg=535)
    assert p.nudged(overlap, -10, None) == (525, None) and p.raw_for(525, 535) == 525
    assert refused(p.nudged, overlap, 10, None) is RefusalCode.LIMITS  # the 540 stop
    near = RotatorStatus("t", MotionState.IDLE, bearing_deg=355, raw_bearing_deg=355)
    assert p.judge(Target(p.nudged(near, 10, None)[0], 0), 355).az_deg == 365


def _at(raw: float, offset: float = 0.0) -> RotatorStatus:
    return RotatorStatus(
        "t", MotionState.IDLE, bearing_deg=norm360(raw + offset), raw_bearing_deg=raw
    )


def test_a_nudge_across_north_stops_at_the_end_where_north_is_an_end() -> None:
    """Rule 6: on a GS-232B, whose 0 and 360 are the ends of a Yaesu rotor's travel, +10 at 350
    goes out as 360, 10 degrees on: folded to 0 it went out as the other end, ``M000``, a turn
    of 350 degrees back through south. A nudge past an end is refused, never taken round; so
    with an offset (a south-centred box's raw 350 + 10 is its 360, not its 0), and from a
    target being approached."""
    for model in ("gs232b", "gs232a", "easycomm2", "rotorcard", "satel", "rc2800", "prosistel"):
        p = Pointing.of(REGISTRY[model])
        for raw, step, sent in ((350, 10, 360), (10, -10, 0), (360, -10, 350), (300, 59.5, 359.5)):
            if model == "satel" and sent == 359.5:
                sent = 360  # its step (protocols/satel.py rule 7): the end nearer, rule 2
            assert p.judge(p.nudge(_at(raw), step, None), raw).az_deg == sent, (model, raw, step)
        for raw, step in ((360, 10), (0, -10), (350, 20), (5, -10)):
            with pytest.raises(Refused) as exc:
                p.nudge(_at(raw), step, None)
            assert exc.value.code is RefusalCode.LIMITS
            assert "past the end" in exc.value.message, (model, raw, step)
    yaesu = Pointing.of(REGISTRY["gs232b"])
    with pytest.raises(Refused) as exc:
        yaesu.nudge(_at(360), 10, None)
    assert exc.value.message.startswith("a nudge of +10 degrees turns to azimuth 10 (controller")
    south = Pointing.of(REGISTRY["gs232b"], offset_deg=180)
    assert south.judge(south.nudge(_at(350, 180), 10, None), 350).az_deg == 360
    assert south.judge(south.nudge(_at(10, 180), -10, None), 10).az_deg == 0
    going = RotatorStatus(
        "t", MotionState.MOVING, bearing_deg=150, target_az_deg=175, raw_target_az_deg=355
    )
    assert south.judge(south.nudge(going, 5, None), 330).az_deg == 360  # from the target
    # limits short of the end: refused, never sent to the other end
    short = Pointing.of(REGISTRY["gs232b"], (0, 359))
    assert refused(short.judge, short.nudge(_at(350), 10, None), 350) is RefusalCode.LIMITS


@pytest.mark.parametrize(
    ("model", "limits", "offset", "raw", "step", "shown"),
    [
        ("gs232b-450", (20, 440), 0, 30, -15, "15, past the limits 20..440 of"),
        ("md01", (10, 530), 0, 15, -10, "5, past the limits 10..530 of"),
        ("gs232b-450", None, 90, 10, -20, "80 (controller -10), past the limits 0..450 ("),
        ("rot2prog", (-180, 400), 0, 395, 10, "45 (controller 405), past the limits -180..400"),
    ],
)
def test_a_nudge_past_a_limit_of_a_scale_that_does_not_wrap_is_refused_not_taken_round(
    model: str,
    limits: tuple[float, float] | None,
    offset: float,
    raw: float,
    step: float,
    shown: str,
) -> None:
    """Rule 6, attack 10: on a scale that does not wrap a nudge goes along the travel from
    where the rotor is, and is refused past a limit. A 450-degree GS-232B with limits 20..440
    at 30, nudged -15, named bearing 15, whose one raw value inside the limits is 375: it was
    sent ``W375`` and turned 345 degrees clockwise. So on an MD-01 (limits 10..530 at 15, -10:
    365) and with an offset at the model's own end (offset 90 at raw 10, -20: raw 350)."""
    p = Pointing.of(REGISTRY[model], limits, offset_deg=offset)
    with pytest.raises(Refused) as exc:
        p.nudge(_at(raw, offset), step, None)
    assert exc.value.code is RefusalCode.LIMITS
    assert exc.value.message.startswith(f"a nudge of {step:+g} degrees turns to azimuth {shown}")
    # up to the limit it goes, the way it names
    short = step / 3
    assert p.judge(p.nudge(_at(raw, offset), short, None), raw).az_deg == raw + short


def test_a_nudge_on_a_scale_that_does_not_wrap_keeps_its_side_of_the_travel() -> None:
    """Rule 6: a nudge's raw value is fixed when it is judged, never left to the side nearest
    the rotor when it is sent (rule 2): a SPID turning from raw 100 to 300, nudged +10, goes
    on to 310 (not -50, 150 degrees from 100 where 310 is 210: the rotor turned back), and at
    rest beside 360 a nudge across it goes on past it on either side."""
    p = Pointing.of(SPID)
    going = RotatorStatus(
        "t",
        MotionState.MOVING,
        bearing_deg=100,
        raw_bearing_deg=100,
        target_az_deg=300,
        raw_target_az_deg=300,
    )
    judged = p.judge(p.nudge(going, 10, None), 100)
    assert (judged.az_deg, judged.true_az_deg) == (310, None)
    assert p.judge(p.nudge(_at(355), 10, None), 355).az_deg == 365
    assert p.judge(p.nudge(_at(365), -10, None), 365).az_deg == 355
    assert p.judge(p.nudge(_at(5), -10, None), 5).az_deg == -5
    assert p.judge(p.nudge(_at(-5), 10, None), -5).az_deg == 5


def _sat(raw: float, el: float = 20.0, *, going_to: float | None = None) -> RotatorStatus:
    if going_to is None:
        return RotatorStatus(
            "t", MotionState.IDLE, bearing_deg=raw, raw_bearing_deg=raw, elevation_deg=el
        )
    return RotatorStatus(
        "t",
        MotionState.MOVING,
        bearing_deg=raw,
        raw_bearing_deg=raw,
        elevation_deg=el,
        target_az_deg=going_to,
        raw_target_az_deg=going_to,
        target_el_deg=el,
    )


@pytest.mark.parametrize(
    ("d_az", "sent"),
    [(5, 130), (-5, 110), (7, 130), (-7, 110), (12, 130), (-12, 110), (16, 140), (-16, 100)],
)
def test_a_satel_nudge_goes_at_least_one_step_its_own_way(d_az: float, sent: float) -> None:
    """Rule 6 on a controller of steps (a SatEL's ten degrees, rule 4): the nearest step of the
    value named, and at least one step on the way it names. Rounded half up alone, -5 at 120
    was 115, sent as 120 (nothing turned), and +5 was 125, sent as 130: lopsided."""
    p = Pointing.of(REGISTRY["satel"])
    assert p.judge(p.nudge(_sat(120), d_az, None), 120).az_deg == sent


def test_satel_nudges_add_up_from_the_step_being_approached_and_in_elevation() -> None:
    """Rule 6: a second press while the first's step is approached counts from that step (the
    status's target, as sent): two presses of +5 or -5 at 120 end two steps on. Elevation
    nudges are stepped the same way; the ends of the travel and the limits still refuse."""
    p = Pointing.of(REGISTRY["satel"])
    first = p.judge(p.nudge(_sat(120), 5, None), 120).az_deg
    assert first == 130
    assert p.judge(p.nudge(_sat(124, going_to=first), 5, None), 124).az_deg == 140
    back = p.judge(p.nudge(_sat(120), -5, None), 120).az_deg
    assert back == 110
    assert p.judge(p.nudge(_sat(117, going_to=back), -5, None), 117).az_deg == 100
    assert p.nudged(_sat(120, 20), 0, 5) == (None, 30)
    assert p.nudged(_sat(120, 20), 0, -5) == (None, 10)
    assert p.nudged(_sat(120, 20), 0, 12) == (None, 30)
    assert p.nudged(_sat(120, 20), 0, 16) == (None, 40)
    assert p.judge(p.nudge(_sat(350), 5, None), 350).az_deg == 360  # the end, not 0
    assert p.judge(p.nudge(_sat(10), -5, None), 10).az_deg == 0
    for raw, d_az in ((360, 5), (0, -5), (0, -6)):
        with pytest.raises(Refused) as exc:
            p.nudge(_sat(raw), d_az, None)
        assert "past the end" in exc.value.message, (raw, d_az)
    low = Pointing.of(REGISTRY["satel"], el_limits=(0.0, 88.0))
    assert refused(low.judge, low.nudge(_sat(120, 80), 0, 5), 120) is RefusalCode.LIMITS
    assert refused(low.judge, low.nudge(_sat(120, 0), 0, -5), 120) is RefusalCode.LIMITS
    fenced = Pointing.of(REGISTRY["satel"], keep_out=((105, 112),))
    assert refused(fenced.judge, fenced.nudge(_sat(120), -5, None), 120) is RefusalCode.KEEP_OUT
    narrowed = Pointing.of(REGISTRY["satel"], az_limits=(0.0, 125.0))
    assert refused(narrowed.judge, narrowed.nudge(_sat(120), 5, None), 120) is RefusalCode.LIMITS
    # a rotor of whole degrees is nudged by the degrees named, as before
    yaesu = Pointing.of(REGISTRY["gs232b"])
    assert yaesu.judge(yaesu.nudge(_sat(120), -5, None), 120).az_deg == 115
    assert yaesu.judge(yaesu.nudge(_sat(120), 3, None), 120).az_deg == 123


def test_a_nudge_across_north_in_the_middle_of_the_travel_is_folded_as_before() -> None:
    """Rule 6: a Hy-Gain rotor's stop is at south, so a Rotor-EZ's or a DCU-1's 0 and 360 are
    one place, the middle of its travel, and an RT-21 is never sent 360: +10 at 355 goes out
    as 5 (``AP1005``), the turn across north the controller makes, and is never refused."""
    for model in ("rotorez", "dcu1", "rt21"):
        p = Pointing.of(REGISTRY[model])
        for raw, step, sent in ((355, 10, 5), (5, -10, 355), (360, 10, 10), (0, -10, 350)):
            assert p.judge(p.nudge(_at(raw), step, None), raw).az_deg == sent, (model, raw, step)
    composite = Pointing.of(composite_spec(EZ, REGISTRY["gs232b"]))
    assert composite.judge(composite.nudge(_at(355), 10, None), 355).az_deg == 5


def test_a_nudge_across_a_hy_gain_rotors_stop_at_south_is_refused_not_taken_round() -> None:
    """Rule 6: a Hy-Gain rotor cannot pass its stop at south, so ``+10`` at 175 sent as
    ``AP1185`` turned it 350 degrees back through north for a nudge (an RT-21, which may turn a
    Hy-Gain rotor too, goes its own way there). Refused, as a nudge past a Yaesu's end is: at
    the stop itself either way, since which end the rotor is at no reading says; up to it and
    across north as before; so with an offset, and from a target being approached."""
    for model in ("rotorez", "dcu1", "rt21"):
        p = Pointing.of(REGISTRY[model])
        for raw, step, sent in ((170, 10, 180), (190, -10, 180), (100, 79, 179), (355, 10, 5)):
            assert p.judge(p.nudge(_at(raw), step, None), raw).az_deg == sent, (model, raw, step)
        for raw, step in ((175, 10), (185, -10), (180, 10), (180, -10), (0, 200), (90, -300)):
            with pytest.raises(Refused) as exc:
                p.nudge(_at(raw), step, None)
            assert exc.value.code is RefusalCode.LIMITS, (model, raw, step)
            assert "south" in exc.value.message, (model, raw, step)
    mounted = Pointing.of(REGISTRY["rotorez"], offset_deg=90)  # raw 175 points at 265
    assert refused(mounted.nudge, _at(175, 90), 10, None) is RefusalCode.LIMITS
    going = RotatorStatus(
        "t", MotionState.MOVING, bearing_deg=100, target_az_deg=175, raw_target_az_deg=175
    )
    assert refused(mounted.nudge, going, 10, None) is RefusalCode.LIMITS  # from the target


@pytest.mark.parametrize("step", [(1e308, None), (-1e300, None), (720, None), (360, None),
                                  (-360, None), (10, 1e308), (0, -400)])  # fmt: skip
def test_a_nudge_of_a_turn_or_more_is_refused(step: tuple[float, float | None]) -> None:
    """Rule 6 (an attack pass): ``1e308`` on ``R/nudge`` turned the rotor to its remainder,
    296 degrees, ``-1e300`` to north, and ``720`` was taken as no step at all; each is refused
    now, and a step just short of a turn is still a nudge."""
    p = Pointing.of(SPID)
    still = RotatorStatus("t", MotionState.IDLE, bearing_deg=100, elevation_deg=10)
    assert refused(p.nudged, still, *step) is RefusalCode.INVALID
    assert p.nudged(still, 359.5, -89) == (99.5, -79)


def test_a_place_becomes_the_great_circle_bearing_from_the_station() -> None:
    berlin, tokyo = geo.parse_locator("JO62qm"), geo.parse_locator("PM95vq")
    az, info = toward(berlin, *tokyo, locator="PM95vq")
    path = geo.great_circle(*berlin, *tokyo)
    assert az == path.short_path_deg and info.distance_km == path.distance_km
    long_az, long_info = toward(berlin, *tokyo, long_path=True)
    assert long_az == pytest.approx(norm360(az + 180))
    assert long_info.path == "long" and long_info.distance_km == path.long_distance_km
    assert refused(toward, None, *tokyo) is RefusalCode.UNSUPPORTED


TENTHS = ["easycomm2", "easycomm3", "rc2800", "rt21", "prosistel-combi"]


@pytest.mark.parametrize("model", TENTHS)
@pytest.mark.parametrize("az", [199.94, 199.95, 199.96, 199.99, 220.01, 220.04, 220.05, 220.06])
def test_keep_out_holds_for_what_a_controller_of_tenths_is_sent(model: str, az: float) -> None:
    """An attack pass: 199.96 went out as 200.0 (rounded half up to tenths), the sector's edge,
    which is inside (rule 3)."""
    spec = REGISTRY[model]
    aim = Pointing.of(spec, keep_out=((200, 220),))
    el = 10.0 if spec.has_elevation else None
    try:
        judged = aim.judge(Target(az, el), None)
    except Refused as exc:
        assert exc.code is RefusalCode.KEEP_OUT and "it takes tenths of a degree" in exc.message
        assert 199.95 <= az < 220.05  # refused only what the codec would put in the sector
        return
    assert judged.az_deg is not None
    wire_az, _ = spec.codec_factory().wire_target(judged.az_deg, judged.el_deg)
    assert not in_sector(wire_az, (200, 220)), f"{az} went out as {wire_az}"


def test_limits_hold_for_what_a_controller_of_tenths_is_sent() -> None:
    aim = Pointing.of(REGISTRY["rt21"], (0.0, 359.95))
    assert aim.judge(Target(359.94), None).az_deg == 359.94  # goes out as 359.9
    with pytest.raises(Refused) as exc:
        aim.judge(Target(359.95), None)  # would go out as 360.0
    assert exc.value.code is RefusalCode.LIMITS
    assert "becomes 360 on the" in exc.value.message and "tenths" in exc.value.message


def test_limits_and_sectors_hold_for_the_satels_ten_degree_step() -> None:
    """protocols/satel.py rule 7: a SatEL is sent the nearest of its rotors' ten-degree steps,
    and the judge checks that (rule 4): 86 of elevation is 90, past a limit of 88; 24 of
    azimuth is 20, a sector's edge; as the elevation box of a composite, the same."""
    satel = REGISTRY["satel"]
    with pytest.raises(Refused) as exc:
        Pointing.of(satel, el_limits=(0.0, 88.0)).judge(Target(100, 86), None)
    assert exc.value.code is RefusalCode.LIMITS
    assert "becomes 90 on the SatEL (it turns in 10-degree steps)" in exc.value.message
    assert Pointing.of(satel, el_limits=(0.0, 88.0)).judge(Target(100, 84), None).el_deg == 84
    aim = Pointing.of(satel, keep_out=((10, 20),))
    assert refused(aim.judge, Target(24, 10), None) is RefusalCode.KEEP_OUT
    assert aim.judge(Target(25, 10), None).az_deg == 25  # goes out as 30
    boxes = composite_spec(REGISTRY["rt21"], satel)
    with pytest.raises(Refused) as exc:
        Pointing.of(boxes, el_limits=(0.0, 88.0)).judge(Target(100.3, 86), None)
    assert "becomes 90" in exc.value.message


@pytest.mark.parametrize(
    ("asked", "at", "raw"),
    [(356.0, 10.0, 0.0), (359.0, 10.0, 0.0), (4.0, 350.0, 360.0), (356.0, 300.0, 360.0),
     (4.0, 100.0, 0.0), (354.0, 10.0, 354.0), (360.0, 10.0, 360.0), (0.0, 350.0, 0.0)],
)  # fmt: skip
def test_a_satel_target_whose_step_is_north_takes_the_end_nearer_the_rotor(
    asked: float, at: float, raw: float
) -> None:
    """Rule 2 with a SatEL's ten-degree steps: 356 and 4 both go out as north, either end of
    its travel, and are sent as the end nearer the rotor; 360 and 0 named stay the ends they
    name. An attack pass: at 10, 356 went out as 360 and the rotor turned 350 degrees."""
    assert Pointing.of(REGISTRY["satel"]).judge(Target(asked, 10), at).az_deg == raw


@pytest.mark.parametrize(
    "model", ["gs232b-az", "rotorcard", "satel", "easycomm2-az", "prosistel", "rc2800-az"]
)
def test_a_north_that_names_neither_end_takes_the_end_nearer_the_rotor(model: str) -> None:
    """Rule 2, attack 10: a group member's bearing that its offset brings to north names
    neither end of a travel whose ends are 0 and 360 (``az_either_end``): the end nearer the
    rotor is sent, 360 from 355 and 0 from 5 (folded to 0, it went out as the far end from
    355, a turn through south); so is the raw north an offset of the rotator's own brings a
    bearing to; the ends the limits, or a group's arc, leave it, as before; 0 and 360 named
    stay the ends they name."""
    aim = Pointing.of(REGISTRY[model])
    north = Target(0.0, az_either_end=True)
    assert [aim.judge(north, at).az_deg for at in (355.0, 5.0, 180.0)] == [360.0, 0.0, 0.0]
    assert aim.judge(north, None).az_deg == 0.0  # no reading: as before
    assert aim.judge(Target(0.0), 355.0).az_deg == 0.0  # named: the end it names
    assert aim.judge(Target(360.0), 5.0).az_deg == 360.0
    south = Pointing.of(REGISTRY[model], offset_deg=180.0)
    assert south.judge(Target(180.0, az_either_end=True), 355.0).az_deg == 360.0
    # the rotator's own target the offset brings to north (helper-521's note on attack 10)
    assert [south.judge(Target(180.0), at).az_deg for at in (355.0, 5.0, None)] == [360.0, 0, 0]
    west = Pointing.of(REGISTRY[model], offset_deg=-10.0)  # the cold review's case: at true 0
    assert west.judge(Target(350.0), 10.0).az_deg == 0.0
    narrowed = Pointing.of(REGISTRY[model], az_limits=(0.0, 355.0))
    assert narrowed.judge(north, 355.0).az_deg == 0.0  # the only end inside the limits
    kept = replace(north, within_deg=(0.0, 200.0))
    assert aim.judge(kept, 190.0).az_deg == 0.0  # 360 turns through 200..360
    assert aim.judge(replace(north, within_deg=(0.0, 360.0)), 355.0).az_deg == 360.0
    judged = aim.judge(north, 355.0)  # kept, to be picked again when sent (review 45)
    assert judged.az_either_end and judged.true_az_deg == 0.0
    assert not aim.judge(kept, 190.0).az_either_end  # (an arc decides it: judged once)


def test_a_satel_step_at_north_keeps_a_groups_arc_and_narrowed_limits() -> None:
    """A review of the rule above: a group member at 190 kept to 0..200 and sent 4 was given
    360, a turn through 200..360 outside the arc (the end nearer the rotor is not taken for a
    target with an arc: it goes out as 0, its own way); and under limits 0..355 the judge took
    raw -4 for 356 (it goes out as 0), which check_raw, the session's check of every part's
    target, refused: the raw value is now the step itself."""
    aim = Pointing.of(REGISTRY["satel"])
    raw = aim.judge(Target(4.0, 10.0, within_deg=(0.0, 200.0)), 190.0).az_deg
    assert raw is not None and aim._sent(raw)[0] == 0.0
    for limits, az, at, step in (
        ((0.0, 355.0), 356.0, 300.0, 0.0),
        ((5.0, 360.0), 2.0, 10.0, 360.0),
    ):
        narrowed = Pointing.of(REGISTRY["satel"], az_limits=limits)
        judged = narrowed.judge(Target(az, 10.0), at)
        assert judged.az_deg == step
        narrowed.check_raw(judged)  # raises if it disagrees


@pytest.mark.parametrize("el_box", ["rt21", "easycomm2", "rc2800", "prosistel-combi", "gs232b"])
def test_a_composite_holds_every_rounding_of_its_boxes(el_box: str) -> None:
    """An attack pass: a SPID azimuth box beside an elevation box of tenths (or whole degrees)
    was judged by the other box's rounding alone, and 10.9 (cut to 10 by the SPID, the edge of
    a sector 350..10, which is inside) was accepted."""
    spec = composite_spec(REGISTRY["rot1prog"], REGISTRY[el_box])  # one pulse a degree
    assert spec.codec_factory().wire_target(10.9, 20.0)[0] == 10.0  # what the box is sent
    aim = Pointing.of(spec, keep_out=((350, 10),))
    with pytest.raises(Refused) as exc:
        aim.judge(Target(10.9, 20.0), 100)
    assert exc.value.code is RefusalCode.KEEP_OUT and "it may cut to whole degrees" in str(
        exc.value.message
    )
    assert aim.judge(Target(11.0, 20.0), 100).az_deg == 11.0


def test_a_composite_judges_each_axis_by_the_box_that_turns_it() -> None:
    """An attack pass: judged by both boxes' ways, an RT-21 azimuth box beside a SPID was
    refused 10.5 next to a sector 350..10 (the RT-21 sends 10.5; the SPID never sees it), and
    a GS-232B's whole degrees refused an RT-21 elevation box 20.3 with limits 20.3..90."""
    rt21_spid = composite_spec(REGISTRY["rt21"], REGISTRY["rot1prog"])
    aim = Pointing.of(rt21_spid, keep_out=((350, 10),))
    assert aim.judge(Target(10.5, 20.0), 100).az_deg == 10.5
    assert rt21_spid.codec_factory().wire_target(10.5, 20.0)[0] == 10.5
    with pytest.raises(Refused):  # 10.04 goes out as 10.0, the sector's edge
        aim.judge(Target(10.04, 20.0), 100)
    gs_rt21 = composite_spec(REGISTRY["gs232b"], REGISTRY["rt21"])
    assert (
        Pointing.of(gs_rt21, el_limits=(20.3, 90.0)).judge(Target(100, 20.3), None).el_deg == 20.3
    )
    with pytest.raises(Refused) as exc:  # but 20.44 goes out as 20.4 (tenths, the RT-21's)
        Pointing.of(gs_rt21, el_limits=(20.42, 90.0)).judge(Target(100, 20.44), None)
    assert "becomes 20.4" in exc.value.message and "tenths" in exc.value.message


def test_keep_out_and_limits_hold_for_what_the_controller_is_really_sent() -> None:
    """Review finding: 199.5 goes out as 200 on a Rotor-EZ (half up), 10.9 as 10 on a SPID at
    one pulse per degree (cut down): a sector's edge, which is inside."""
    ez = Pointing.of(EZ, keep_out=((200, 220),))
    assert refused(ez.judge, Target(199.5), None) is RefusalCode.KEEP_OUT
    assert ez.judge(Target(199.4), None).az_deg == 199.4  # goes out as 199
    shifted = Pointing.of(EZ, offset_deg=0.3, keep_out=((200, 220),))
    assert refused(shifted.judge, Target(199.9), None) is RefusalCode.KEEP_OUT  # raw 200: 200.3
    spid = Pointing.of(SPID, keep_out=((0, 10),))
    with pytest.raises(Refused) as exc:
        spid.judge(Target(10.9, 0), 100)
    assert exc.value.code is RefusalCode.KEEP_OUT
    assert "sent to the" in exc.value.message and "10..10.9" in exc.value.message
    assert spid.judge(Target(11, 0), 100).az_deg == 11
    narrow = Pointing.of(SPID, keep_out=((20.2, 20.4),))  # inside one degree's step
    assert refused(narrow.judge, Target(20.6, 0), 100) is RefusalCode.KEEP_OUT
    # the lower limit: 10.7 would go out as 10 on a SPID limited to 10.5..
    assert refused(Pointing.of(SPID, (10.5, 300)).judge, Target(10.7, 0), 100) is (
        RefusalCode.LIMITS
    )
    # the codec's cut is floor(360 + v) - 360: a hair below 0 goes out as 0, not -1
    assert Pointing.of(SPID, (-0.5, 300)).judge(Target(-1e-15, 0), 100).az_deg == -1e-15
    with pytest.raises(Refused) as exc:
        Pointing.of(SPID, (0.5, 300)).judge(Target(0.7, 0), 100)
    assert "it may cut to whole degrees, its coarsest resolution" in exc.value.message
    with pytest.raises(Refused) as exc:
        Pointing.of(SPID, keep_out=((350, 10),)).judge(Target(365, 0), 100)
    assert exc.value.message.startswith("azimuth 365 (5) is in the keep-out sector 350..10")


def test_nudges_count_from_where_the_rotor_is_going_on_either_side() -> None:
    p = Pointing.of(SPID)
    # a second press during the brake delay adds to the first (review finding: 115, not 220)
    braking = RotatorStatus(
        "t", MotionState.BRAKING, bearing_deg=105, target_az_deg=210, raw_target_az_deg=210
    )
    assert p.nudged(braking, 10, None) == (220, None)
    # a long move on a SPID: from raw 530 to raw 200, at raw 450 (true 90); +10 is true 210,
    # not 570 past the stop (review finding)
    long_move = RotatorStatus(
        "t",
        MotionState.MOVING,
        bearing_deg=90,
        raw_bearing_deg=450,
        target_az_deg=200,
        raw_target_az_deg=200,
    )
    assert p.nudged(long_move, 10, None) == (210, None)
    assert p.judge(Target(210, 0), 450).az_deg == 210  # 570 would be past the 540 stop
    # a rotor with no brake is idle while it settles, its target still waiting: the same
    settling = RotatorStatus(
        "t", MotionState.IDLE, bearing_deg=105, target_az_deg=210, raw_target_az_deg=210
    )
    assert p.nudged(settling, 10, None) == (220, None)
    at_rest = RotatorStatus("t", MotionState.IDLE, bearing_deg=105, raw_bearing_deg=105)
    assert p.nudged(at_rest, 10, None) == (115, None)
    stalled = RotatorStatus("t", MotionState.STALLED, bearing_deg=105, target_az_deg=210)
    assert p.nudged(stalled, 10, None) == (115, None)  # stuck: from where it is
    assert refused(p.nudged, stalled, 0, None) is RefusalCode.INVALID


@pytest.mark.parametrize("offset_deg", [180.0, -179.7, 10.3, -0.1, 0.0])
@pytest.mark.parametrize("raw_deg", [0.0, 5.7, 220.3, 400.3, 449.7])
def test_a_reading_unfolds_to_raw_plus_the_offset_read_from_its_true_bearing(
    offset_deg: float, raw_deg: float
) -> None:
    """Rule 2: ``unfolded`` gives raw + offset from the true bearing and the raw value alone
    (the remote knows no offset), a south-centred rotor's 180 too where rounding puts the
    difference a hair past -180."""
    aim = Pointing.of(REGISTRY["gs232b-az-450"], offset_deg=offset_deg)
    assert unfolded(aim.true_of(raw_deg), raw_deg) == pytest.approx(raw_deg + offset_deg)
    assert unfolded(None, raw_deg) is None and unfolded(40.0, None) is None


def test_a_refused_nudge_just_short_of_a_turn_is_named_as_sent() -> None:
    """An attack pass: a nudge of 359.9999 across a Hy-Gain's stop at south was refused as
    ``+360``, which reads as the turn a nudge may not be."""
    p = Pointing.of(EZ)
    still = RotatorStatus("t", MotionState.IDLE, bearing_deg=100, raw_bearing_deg=100)
    with pytest.raises(Refused, match=r"a nudge of \+359\.9999 degrees"):
        p.nudge(still, 359.9999, None)


def test_narrowed_limits_on_a_travel_through_north_hold_along_the_turn() -> None:
    """Rule 4: a Hy-Gain rotor's stop is at south (raw 180), so its turns between east and west
    cross north; limits that leave part of the scale out hold along the turn, not at its end
    alone. Without a reading, its end is checked as before (the way is not known)."""
    ez = Pointing.of(EZ, az_limits=(20.0, 340.0))
    assert refused(ez.judge, Target(330), 30) is RefusalCode.LIMITS  # 30 -> 330 via north
    assert refused(ez.judge, Target(200), 100) is RefusalCode.LIMITS  # 100 -> 200 via north
    assert ez.judge(Target(170), 30).az_deg == 170
    assert ez.judge(Target(330), 200).az_deg == 330  # the west side
    assert ez.judge(Target(330), None).az_deg == 330  # no reading: its end
    assert ez.judge(Target(100), 5).az_deg == 100  # turned outside by hand: back in, the least out
    near = Pointing.of(EZ, az_limits=(0.0, 350.0))
    assert refused(near.judge, Target(10), 340) is RefusalCode.LIMITS  # through 350..360
    assert near.judge(Target(10), 100).az_deg == 10
    shifted = Pointing.of(EZ, az_limits=(20.0, 340.0), offset_deg=-10.0)  # raw 20 is true 10
    assert refused(shifted.judge, Target(320), 30) is RefusalCode.LIMITS  # raw 30 -> 330
    assert shifted.judge(Target(160), 30).az_deg == 170
    yaesu = Pointing.of(REGISTRY["gs232b"], az_limits=(20.0, 340.0))  # its ends are at north
    assert yaesu.judge(Target(330), 30).az_deg == 330


def test_narrowed_limits_leave_an_rt21_its_way_and_a_hy_gain_rotor_off_its_stop() -> None:
    """Rule 4, a review: an RT-21 may turn a Yaesu through south, so its limits are judged at
    the end as before (with 2..358 it could no longer leave its half); a Hy-Gain rotor is not
    sent to its stop under narrowed limits (there no reading tells which end it is at), and
    one found there is told why nothing goes, not refused in silence."""
    rt21 = Pointing.of(REGISTRY["rt21"], az_limits=(2.0, 358.0))
    assert rt21.judge(Target(270), 90).az_deg == 270
    assert rt21.judge(Target(200), 10).az_deg == 200
    ez = Pointing.of(EZ, az_limits=(20.0, 340.0))
    for at in (30.0, None):  # (None: presets and the park position, checked at load)
        for az in (180.0, 179.6, 180.4):  # (an attack pass: 179.6 went out as AP1180)
            with pytest.raises(Refused, match="as its stop .controller 180.*send 179 or 181"):
                ez.judge(Target(az), at)
    south = Pointing.of(EZ, az_limits=(20.0, 340.0), offset_deg=180.0)  # (true bearings: the
    with pytest.raises(Refused, match="send 359 or 1$"):  # advice too, an attack pass)
        south.judge(Target(0), 30)
    assert south.judge(Target(359), 100).az_deg == 179
    assert ez.judge(Target(179), 30).az_deg == 179
    with pytest.raises(Refused, match="is at its stop .controller 180.*off the stop"):
        ez.judge(Target(90), 180)
    assert Pointing.of(EZ).judge(Target(180), 30).az_deg == 180  # whole limits: as before


def test_a_satel_nudge_of_less_than_half_a_step_is_refused() -> None:
    """Rule 6, a review: a nudge of 0.001 turned a SatEL a whole ten-degree step."""
    satel = Pointing.of(REGISTRY["satel"])
    for d_az, d_el in ((0.001, None), (-4.9, None), (0.0, 1.0)):
        with pytest.raises(Refused, match="less than half of the SatEL's 10-degree step"):
            satel.nudge(_sat(120, 20), d_az, d_el)
    assert satel.nudge(_sat(120, 20), 5.0, None).az_deg == 130
    # a reading off its step is the rotor on the step nearest (an attack pass: at 121, -5 went
    # out as 120, where it stood)
    assert satel.judge(satel.nudge(_sat(121, 20), -5.0, None), 121).az_deg == 110
    assert satel.judge(satel.nudge(_sat(119, 20), 5.0, None), 119).az_deg == 130


def test_a_group_s_arc_is_judged_on_the_step_a_satel_is_sent() -> None:
    """Rule 9 with rule 4: a SatEL's 335 goes out as 340, outside a group's 20..335; judged on
    the value named, it was taken (an attack pass)."""
    satel = Pointing.of(REGISTRY["satel"])
    assert refused(satel.judge, Target(335, 10, within_deg=(20, 335)), 100) is RefusalCode.LIMITS
    assert satel.judge(Target(334, 10, within_deg=(20, 335)), 100).az_deg == 334  # sent as 330
    assert satel.judge(Target(335, 10, within_deg=(20, 340)), 100).az_deg == 335
