"""A Prosistel D and a Combi-Track in virtual time: the position output turned off first, bearings
straight out (whole degrees, tenths), the hard stop at once, a new bearing while turning without
a stop, a box streaming its position read right, a glitched reply never read, a bearing the box
refuses reported refused, and a satellite pass followed in azimuth and elevation by the
Combi-Track.

The box takes a new bearing at any time and brakes by itself, answers every frame (``STX A,G,R``
to a bearing, ``STX A,?,123,B`` to a query) and reads its rotor in whole degrees (D) or tenths
(Combi-Track, two units). 9600 baud: one poll of a D (4 bytes out, 11 back) takes 16 ms of the
line, of a Combi-Track (8 out, 24 back) 33 ms.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge import emulators
from bridge.core.model import MotionState
from bridge.emulators.prosistel import Outcome
from bridge.protocols.base import JunkReply
from bridge.protocols.prosistel import COMBI_TRACK, D_AZIMUTH, ProsistelCodec
from tests.engine.test_session_tracking import a_pass_that, fly
from tests.engine.virtual import VirtualRotator, moves, settled_at

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
MODELS = ("prosistel", "prosistel-combi")
HARD_STOP = {"prosistel": [b"\x02AG999\r"], "prosistel-combi": [b"\x02AG9999\r", b"\x02BG9999\r"]}


def ready(rig: Rig, model: str = "prosistel", **emulator: object) -> VirtualRotator:
    v = rig(model, emulator={**FAST, **emulator})
    v.run_until_state(IDLE, 30)
    return v


@pytest.mark.parametrize(
    ("model", "wire", "at"),
    [
        ("prosistel", [b"\x02AG123\r"], (123.0, None)),
        ("prosistel-combi", [b"\x02AG1235\r", b"\x02BG0\r"], (123.5, 0.0)),
    ],
)
def test_a_target_goes_out_after_the_output_is_off_and_is_read_back(
    rig: Rig, model: str, wire: list[bytes], at: tuple[float, float | None]
) -> None:
    v = ready(rig, model, start_az_deg=10)
    first = [f.outcome for f in v.frames()][: len(HARD_STOP[model])]
    assert set(first) == {Outcome.OUTPUT_OFF}  # before anything else
    v.target(123.46)
    v.run_until(settled_at(*at), 60, f"at {at}")
    assert moves(v) == wire
    assert v.status.bearing_deg == at[0] and v.errors() == []


@pytest.mark.parametrize("model", MODELS)
def test_a_stop_while_turning_is_the_hard_stop_at_once(rig: Rig, model: str) -> None:
    v = ready(rig, model)
    v.target(300)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 30, 30, "turning")
    t = v.now
    v.stop()
    assert [w.t for w in v.writes if w.data == b"".join(HARD_STOP[model])] == [t]  # at once
    v.run_until(lambda h: h.state is IDLE, 10, "idle")
    truth = v.truth()
    assert not truth.is_moving and 30 < truth.az_deg < 40
    assert v.status.bearing_deg == pytest.approx(truth.az_deg, abs=0.51)
    assert [f.data for f in v.frames(Outcome.STOP)] == HARD_STOP[model] and v.errors() == []


def test_a_new_target_while_turning_goes_straight_out_without_a_stop(rig: Rig) -> None:
    v = ready(rig)
    v.target(200)
    v.run_until(lambda h: h.truth().az_deg > 50, 30, "turning")
    t = v.now
    v.target(20)
    v.run_until(lambda h: moves(h, t), 2, "the new bearing")
    assert v.truth().is_moving and moves(v, t) == [b"\x02AG20\r"]
    v.run_until(settled_at(20.0), 120, "at 20")
    assert v.frames(Outcome.STOP) == []


@pytest.mark.parametrize("model", MODELS)
def test_a_box_streaming_its_position_after_a_power_cycle_is_read_right(
    rig: Rig, model: str
) -> None:
    """A box that streams again after a power cycle (fast: every 40 ms) is no trouble: every
    bearing published is one the rotor passed through, nothing is reported, a target arrives."""
    v = ready(rig, model, start_az_deg=100, streaming=True, stream_interval_s=0.04)
    v.power_cycle()
    t = v.now
    v.target(150)
    v.run_until(settled_at(150.0, 0.0 if model == "prosistel-combi" else None), 60, "at 150")
    v.run_for(10)
    assert v.truth().streaming  # the box went on streaming all along
    bearings = {s.bearing_deg for s in v.published(since=t)} - {None}
    assert bearings and all(100.0 <= b <= 150.0 for b in bearings if b is not None)
    assert v.status.bearing_deg == 150.0 and v.errors() == []


@pytest.mark.parametrize(
    ("model", "line", "lost", "tail"),
    [("prosistel", 11, 3, b"?,050,B"), ("prosistel-combi", 12, 8, b"0,B")],
)
def test_a_streaming_box_whose_line_the_ports_opening_cut_is_read_right_and_no_error(
    rig: Rig, model: str, line: int, lost: int, tail: bytes
) -> None:
    """The port opens while a streaming box is mid-line: the bridge's first bytes are that
    line's tail, without its STX. It is no reading and no error; the box is read right. (A
    flake under load: an open's flush took a streamed line's head, and R/error said the bytes
    were no valid reply.)"""
    v = rig(model, connect=False, emulator={**FAST, "start_az_deg": 50, "streaming": True})
    v.run_until(lambda h: h.lost_to_host > 0, 5, "streaming")  # (a line's first byte)
    v.run_until(lambda h: h.lost_to_host % line == lost, 1, "mid-line")  # (a line a unit)
    v.link_up()
    v.run_until_state(IDLE, 30)
    v.run_for(5)
    assert b"".join(data for _t, data in v.received).split(b"\r")[0] == tail  # (no STX)
    assert v.status.bearing_deg == 50.0 and v.errors() == []


def test_a_glitched_reply_before_the_real_one_is_no_reading(rig: Rig) -> None:
    v = ready(rig, "prosistel-combi", start_az_deg=100, start_el_deg=20)
    v.run_for(10)
    glitched = v.glitch_once(b"\x02", b"\xff\x02A,?,3599,B\r")
    t = v.now
    v.run_for(30)
    assert glitched
    assert {(s.bearing_deg, s.elevation_deg) for s in v.published(since=t)} <= {(100.0, 20.0)}
    assert v.state is IDLE


def test_a_bearing_the_box_refuses_is_sent_once_more_then_reported_refused_and_nothing_moves(
    rig: Rig,
) -> None:
    """A bearing the box cannot take (a flipped bit made 150 450) moves nothing: the same bearing
    goes once more (controller.py rule 11), and refused again (``STX A,G,E,00001``) it is
    reported refused at once, the rotor at rest where it was (prosistel.py rule 3; before: the
    answer reported as junk, and 10 s later a stall blaming the brake or a stuck rotor)."""
    v = ready(rig, start_az_deg=77)
    t = v.now
    v.garble_writes(b"\x02AG150\r", b"\x02AG450\r", count=2)  # a bearing the box cannot take
    v.target(150)
    v.run_until(lambda h: h.errors("refused", since=t), 2, "the refusal")
    v.run_until_state(IDLE, 1)
    assert [e.kind for e in v.errors(since=t)] == ["refused"]
    assert [f.data for f in v.frames(Outcome.REFUSED)] == [b"\x02AG450\r"] * 2
    v.run_for(15)
    assert v.errors("stalled", since=t) == []
    assert v.truth().az_deg == 77 and not v.truth().is_moving
    assert {s.bearing_deg for s in v.published(since=t)} - {None} == {77.0}


def test_a_bearing_the_box_refused_once_goes_on_the_try_more(rig: Rig) -> None:
    v = ready(rig, start_az_deg=77)
    t = v.now
    v.garble_writes(b"\x02AG150\r", b"\x02AG450\r")
    v.target(150)
    v.run_until(lambda h: h.state is IDLE and v.truth().az_deg == 150, 60, "at 150")
    assert v.errors(since=t) == []  # the refusal is the target's, and the try more took
    assert len(v.frames(Outcome.REFUSED)) == 1


def test_an_elevation_the_combi_track_refuses_is_no_refusal_of_a_target_its_azimuth_turns_to(
    rig: Rig,
) -> None:
    """prosistel.py rule 3: the Combi-Track's target is a ``G`` per unit, each answered for its
    own: an error to the elevation's refuses that frame alone, and the azimuth's turns the
    rotor; it is reported, never as the target's refusal."""
    v = ready(rig, "prosistel-combi", start_az_deg=10)
    v.garble_writes(b"\x02BG450\r", b"\x02BG9450\r", count=2)
    t = v.now
    v.target(200, 45)
    v.run_until(lambda h: h.truth().az_deg == 200 and not h.truth().is_moving, 60, "at 200")
    assert v.errors("refused", since=t) == [] and v.errors("protocol", since=t)
    assert len(v.frames(Outcome.REFUSED, since=t)) == 2


def test_a_satellite_pass_is_followed_by_the_combi_track_within_3_degrees() -> None:
    """A Combi-Track (6 and 3 deg/s here) follows a pass clear of north (a 360-degree azimuth
    cannot cross it without a turn round) as closely as the SPIDs do: tenths both ways."""
    v, errors = fly("prosistel-combi", a_pass_that(across_north=False))
    with v:
        worst_az = max(e[1] for e in errors[5:])  # the body rises at the horizon's edge
        worst_el = max(e[2] for e in errors[5:])
        assert worst_az <= 3.0 and worst_el <= 3.0, (worst_az, worst_el)
        assert len(moves(v)) >= 10 and not v.frames(Outcome.REFUSED)
        assert v.errors() == []


@pytest.mark.parametrize(
    ("model", "glitch"),
    [
        ("prosistel", b"\x02A,?,364,B\r"),  # out of range, past its slack (rule 1)
        ("prosistel", b"\x02A,?,0450,B\r"),  # a Combi-Track's width
        ("prosistel", b"\x02E,?,045,B\r"),  # a unit this box has not got
        ("prosistel-combi", b"\x02B,?,0950,B\r"),  # an elevation above 90
        ("prosistel-combi", b"\x02A,?,450,B\r"),  # a D's width
    ],
)
def test_a_position_the_box_cannot_say_is_told_once_and_changes_nothing(
    rig: Rig, model: str, glitch: bytes
) -> None:
    """Rule 2 (an attack pass): a line shaped like a position that is out of range, of the other
    family's width or of a unit the box has not got, just before a poll's answer: it was
    dropped and the poll asked again, but nobody was told, as if it were the box's chatter."""
    v = ready(rig, model, start_az_deg=77, start_el_deg=20 if model == "prosistel-combi" else 0)
    v.run_for(3)
    t = v.now
    glitched = v.glitch_once(b"\x02", glitch)
    v.run_for(10)
    want = (77.0, 20.0 if model == "prosistel-combi" else None)
    assert glitched and {(s.bearing_deg, s.elevation_deg) for s in v.published(since=t)} <= {want}
    assert len(v.errors("protocol", since=t)) == 1 and v.state is IDLE and not moves(v)


def test_a_bare_azimuth_to_a_combi_track_keeps_its_elevation(rig: Rig) -> None:
    v = ready(rig, "prosistel-combi", start_az_deg=10, start_el_deg=30)
    v.target(100)  # no elevation named: unit B must not be sent to 0
    v.run_until(settled_at(100, 30), 60, "at 100/30")
    assert moves(v) == [b"\x02AG1000\r", b"\x02BG300\r"]


@pytest.mark.parametrize(
    ("model", "box", "start_az_deg", "misread"),
    [
        ("prosistel", "prosistel-combi", 35.0, 350.0),  # 0350: tenths read as degrees
        ("prosistel-combi", "prosistel", 290.0, 29.0),  # 290: degrees read as tenths
    ],
)
def test_a_box_of_the_other_family_gives_no_reading(
    rig: Rig, model: str, box: str, start_az_deg: float, misread: float
) -> None:
    """A D answers in whole degrees (three digits), a Combi-Track in tenths, always four
    (Hamlib's examples: ``A,?,290,R``, ``B,?,0900,R``): a reply of the other width is a box
    set up as the wrong model, never a bearing ten times off."""
    v = rig(model, connect=False)
    v.device = emulators.create(box, now=v.now, start_az_deg=start_az_deg, **FAST)
    v.link_up()
    v.run_for(30)
    assert all(s.bearing_deg != misread for s in v.published())
    assert not v.status.available and v.status.bearing_deg is None


def test_the_other_familys_width_is_named_in_the_detail() -> None:
    codec = ProsistelCodec(D_AZIMUTH)
    codec.encode_query()
    [junk] = codec.feed(b"\x02A,?,0350,B\r")
    assert isinstance(junk, JunkReply) and "Combi-Track" in junk.detail
    combi = ProsistelCodec(COMBI_TRACK)
    combi.encode_query()
    [junk] = combi.feed(b"\x02A,?,290,B\r\x02B,?,0450,B\r")
    assert isinstance(junk, JunkReply) and "(a D)" in junk.detail
