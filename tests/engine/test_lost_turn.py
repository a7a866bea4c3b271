"""session/controller.py rule 13: a single controller's port lost mid-turn says what became of
the turn (dropped, its target in true bearings, left to the controller, a STOP sent meanwhile
first); one lost at rest or after a stop names no turn, and a composite's box says its port's
words alone (runtime/composite.py rule 8 stops the rotator's turn there)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState, Target
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite

UNPLUGGED = "serial link lost (adapter unplugged?)"
SEEN = "followed by its readings once the port is back, and stopped if it comes to rest short of it"
AFTER = (
    "a STOP sent meanwhile goes first when the port is back; send the target again to have "
    "the turn watched"
)


def test_an_az_el_turn_is_named_by_its_true_azimuth_and_its_elevation(
    rig: Callable[..., VirtualRotator],
) -> None:
    v = rig("rot2prog", settings={"az_offset_deg": 10})
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, 20)  # (raw, as the judge hands it on: 210 true)
    v.run_until(lambda h: h.truth().is_moving, 20, "turning")
    v.run_for(1)
    assert (v.status.target_az_deg, v.status.target_el_deg) == (210, 20)  # as shown
    t = v.now
    v.link_down(UNPLUGGED)
    said = [r.message for r in v.errors("serial", since=t)]
    assert said == [
        f"{UNPLUGGED}: its turn to 210°, elevation 20° was dropped, and the controller may "
        f"finish it by itself ({SEEN}); {AFTER}"
    ]
    assert v.status.last_error == said[0]


def test_a_dcu1_turn_is_said_unseen(rig: Callable[..., VirtualRotator]) -> None:
    v = rig("dcu1")
    v.run_for(5)
    v.target(120)
    v.run_until(lambda h: h.truth().is_moving, 20, "turning")
    t = v.now
    v.link_down(UNPLUGGED)
    said = [r.message for r in v.errors("serial", since=t)]
    assert said == [
        f"{UNPLUGGED}: its turn to 120° was dropped, and the controller may finish it by "
        f"itself (unseen, not stopped); {AFTER}"
    ]


def test_a_port_lost_at_rest_or_after_a_stop_names_no_turn(
    rig: Callable[..., VirtualRotator],
) -> None:
    v = rig("rotorez")
    v.run_until_state(MotionState.IDLE, 30)
    t = v.now
    v.link_down(UNPLUGGED)
    assert [r.message for r in v.errors("serial", since=t)] == [UNPLUGGED]
    v.link_up()
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200)
    v.run_until(lambda h: h.truth().is_moving, 20, "turning")
    v.stop()
    v.run_for(0.5)
    t = v.now
    v.link_down(UNPLUGGED)
    assert [r.message for r in v.errors("serial", since=t)] == [UNPLUGGED]


def test_a_composite_box_lost_mid_turn_says_its_port_alone() -> None:
    """The box's words are its port's: the rotator's turn is stopped in the other box at once
    and owed in this one (runtime/composite.py rule 8), not left to the controller."""
    with VirtualComposite("easycomm3", "gs232b") as v:
        v.run_until(lambda h: h.status.available, 20)
        v.run_for(1.0)
        v.aim(Target(200.0, 60.0))
        v.run_until(lambda h: h.az.truth().az_deg > 8 and h.el.truth().el_deg > 4, 30)
        t = v.now
        v.az.link_down(UNPLUGGED)
        v.run_for(0.1)
        assert [r.message for r in v.az.errors("serial", since=t)] == [UNPLUGGED]
        assert v.status.last_error == UNPLUGGED


@pytest.mark.parametrize("model", ["gs232b", "easycomm3", "rotorez"])
def test_a_rotor_jammed_while_its_port_was_out_is_stopped_at_its_first_rest(model: str) -> None:
    """Rule 13: with the turn's target dropped no stall was judged after the replug, and the
    motor drove the jammed rotor for good under an idle status, nothing said."""
    with VirtualRotator(model) as v:
        v.run_until(lambda h: h.status.available, 20)
        v.run_for(10)
        v.target(200, 0) if v.cfg.spec.has_elevation else v.target(200)
        v.run_until(lambda h: h.truth().az_deg > 20, 30)
        t = v.now
        v.link_down(UNPLUGGED)
        v.run_for(1.0)
        v.jam()
        v.link_up()
        v.run_for(60)
        assert not v.truth().is_moving  # observed: the motor still driving, two minutes on
        stops = [e.message for e in v.errors("stop", since=t)]
        assert len(stops) == 1, stops
        at, rest = stops[0].removeprefix("rotor at rest at ").split("° since its port came back")
        assert abs(float(at) - v.truth().az_deg) < 1, stops  # where it stands, jammed
        assert rest.startswith(", short of its turn to 200°"), stops
        assert v.status.state is MotionState.IDLE and v.status.target_az_deg is None


def test_a_turn_finished_by_itself_after_the_replug_gets_no_stop(
    rig: Callable[..., VirtualRotator],
) -> None:
    """Rule 13: the user's own move, followed to its end, is not stopped (controller.py rule
    10's review), nor is a rotor found at its target at the replug."""
    v = rig("gs232b")
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, 10)
    v.run_until(lambda h: h.truth().az_deg > 20, 30)
    t = v.now
    v.link_down(UNPLUGGED)
    v.run_for(1.0)
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 120, "at rest")
    v.run_for(30)
    stop = v.cfg.spec.codec_factory().encode_stop()
    assert stop not in v.sent(since=t) and v.errors("stop", since=t) == []
    assert abs(v.truth().az_deg - 200) < 2


def test_a_satel_turn_is_said_stopped_by_the_replug_and_gets_no_stop_error(
    rig: Callable[..., VirtualRotator],
) -> None:
    """Rule 13: a SatEL's connect begins with its stop (protocols/satel.py rule 2), so the
    replug stops its turn: the port error says so, and the rest after it is no jam (a cold
    review: the error promised the controller would finish the turn, followed, and the replug,
    having stopped it at 69°, sent it a second stop with a ``stop`` error blaming a jam, the
    panel or a power cut)."""
    v = rig("satel")
    v.run_until(lambda h: h.status.available, 20)
    v.run_for(10)
    v.target(200, 10)
    v.run_until(lambda h: h.truth().az_deg > 60, 60)
    t = v.now
    v.link_down(UNPLUGGED)
    said = [r.message for r in v.errors("serial", since=t)]
    assert said == [
        f"{UNPLUGGED}: its turn to 200°, elevation 10° was dropped, and the replug stops it "
        "(the controller's connect begins with a stop); send the target again"
    ]
    v.run_for(1.0)
    v.link_up()
    v.run_for(60)
    stop = v.cfg.spec.codec_factory().encode_stop()
    assert [f.data for f in v.frames(since=t) if f.data == stop] == [stop]  # the connect's
    assert v.errors("stop", since=t) == []
    assert not v.truth().is_moving and v.truth().az_deg < 100


@pytest.mark.parametrize("answers_first", [False, True])
def test_a_lost_turn_no_reading_watches_after_the_replug_is_stopped(answers_first: bool) -> None:
    """Rules 13 and 2: the turn the port dropped is judged by the readings after the replug;
    where none come (a controller that does not answer once the port is back, or one that
    falls silent before the rotor rests) no reading can judge it, and a motor driving a rotor
    jammed meanwhile drove on for good (a cold review: 'does not answer' said, the motor
    still driving a minute on). As for a turn under way that goes silent, it is stopped in
    case the controller still hears."""
    with VirtualRotator("gs232b") as v:
        v.run_until(lambda h: h.status.available, 20)
        v.run_for(10)
        v.target(200, 0)
        v.run_until(lambda h: h.truth().az_deg > 20, 30)
        t = v.now
        v.link_down(UNPLUGGED)
        v.run_for(1.0)
        v.jam()
        if answers_first:
            v.link_up()
            v.run_until(lambda h: h.status.available, 10, "answering")
            v.set_silent(True)
        else:
            v.set_silent(True)
            v.link_up()
        v.run_for(60)
        assert not v.truth().is_moving  # observed: the motor still driving the jam
        said = [e.message for e in v.errors("serial", since=t)][1:]
        assert len(said) == 1 and "a stop sent, in case it still hears" in said[0], said


def test_a_rest_short_on_its_elevation_names_where_the_elevation_stands(
    rig: Callable[..., VirtualRotator],
) -> None:
    """Rule 13's stop error says where the rotor rests on the axis short of the turn: an
    elevation turn jammed while the port was out read 'at rest at 10°, short of its turn to
    10°, elevation 80°', its azimuth alone, as if it stood at its target (a cold review)."""
    v = rig("gs232b", emulator={"start_az_deg": 10.0})
    v.run_until(lambda h: h.status.available, 20)
    v.run_for(10)
    v.target(None, 80)
    v.run_until(lambda h: h.truth().el_deg > 20, 60)
    t = v.now
    v.link_down(UNPLUGGED)
    v.run_for(1.0)
    v.jam()
    v.link_up()
    v.run_for(60)
    assert not v.truth().is_moving
    (stop,) = [e.message for e in v.errors("stop", since=t)]
    at, rest = stop.removeprefix("rotor at rest at 10°, elevation ").split("° since its port", 1)
    assert abs(float(at) - v.truth().el_deg) < 1, stop  # where the elevation stands, jammed
    assert rest.startswith(" came back, short of its turn to 10°, elevation 80° dropped"), stop


def test_a_port_lost_with_a_stop_waiting_for_the_line_names_no_turn(
    rig: Callable[..., VirtualRotator],
) -> None:
    """Rule 13: a STOP taken while a half-duplex line owed a reply waits for it (link.py rule
    3); the port lost then owes it, the first frame back. The error named the turn left to the
    controller to finish, under the operator's STOP (a cold review, a Rot2Prog)."""
    v = rig("rot2prog")
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, 20)
    v.run_until(lambda h: h.truth().az_deg > 20, 60, "turning")
    poll = v.cfg.spec.codec_factory().encode_query()
    v.run_until(lambda h: h.writes[-1].data == poll and h.writes[-1].t == h.now, 5, "a poll")
    v.stop()
    t = v.now
    v.link_down(UNPLUGGED)
    assert [r.message for r in v.errors("serial", since=t)] == [UNPLUGGED]
    v.run_for(1.0)
    v.link_up()
    v.run_for(30)
    stop = v.cfg.spec.codec_factory().encode_stop()
    assert [f.data for f in v.frames(since=t)][:1] == [stop]  # the STOP owed, first back
    assert not v.truth().is_moving and v.truth().az_deg < 40
    assert v.errors("stop", since=t) == []
