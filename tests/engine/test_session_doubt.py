"""A reading of a rotor not turning, far from where it stands, is asked again before it is
believed (session/controller.py rule 9), and a composite box's axis that never turns changes
only when said twice (protocols/axes.py rule 5): one a flipped bit made well-formed is never
published, never taken as a move and never sent back to a controller; a move by hand is
believed on the next reading. (The second half of the file: a cold review's reproductions of
where the first form of the rule did not reach.)"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import pytest

from bridge.core.model import ErrorKind, MotionState, Target
from bridge.protocols.axes import Axis
from bridge.session import controller as C
from bridge.session.stops import STOP_UNSURE_S
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite

Rig = Callable[..., VirtualRotator]
# every model whose replies carry the bearing as ASCII digits (SPID's are raw bytes)
MODELS = ["rotorez", "rotorcard", "gs232b", "gs232a", "easycomm2", "rt21", "prosistel", "satel"]


def at_rest(rig: Rig, model: str) -> VirtualRotator:
    """At rest at 150 (settled), polled at its idle rate; a turn by hand followed (an Easycomm
    would stop it: controller.py rule 10)."""
    v = rig(model, settings={"unasked_moves": "follow"})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.aim(Target(150.0, None))
    v.run_until(lambda h: h.state is MotionState.IDLE and h.now > 10, 200, "at 150")
    v.run_for(10)
    assert v.status.bearing_deg is not None and 100 <= v.status.bearing_deg < 200  # (overshoot)
    return v


def locked_at_rest(rig: Rig, model: str) -> tuple[VirtualRotator, float]:
    """``at_rest``, then locked and 5 s on (the lock's stop written and checked); returns the
    rotator and the bearing it rests at."""
    v = at_rest(rig, model)
    rest = v.status.bearing_deg
    assert rest is not None
    v.lock(True)
    v.run_for(5)
    return v, rest


def flip_next_hundreds(v: VirtualRotator) -> list[float]:
    """One bit flipped on the line in the next reply: its bearing's hundreds digit, 1 -> 3
    (0x31 -> 0x33): 150 reads 350. Returns the list the instant goes into."""
    when: list[float] = []
    before = bytearray(b"  ")  # the two bytes before (the device's output comes byte by byte)

    def flip(data: bytes, now: float) -> bytes:
        out = bytearray()
        for b in data:  # the first digit after the bearing's head
            if (
                not when
                and b == ord("1")
                and (before[-1] in b";=,Z" or before[-2:] in (b"= ", b"+0"))
            ):
                when.append(now)
                b = ord("3")
            before[:] = before[-1:] + bytes([b])
            out.append(b)
        return bytes(out)

    v.to_host = flip
    return when


def flip_and_wait(v: VirtualRotator) -> float:
    """``flip_next_hundreds``, and 20 s after the flipped reply came; returns when it was armed."""
    t = v.now
    flipped = flip_next_hundreds(v)
    v.run_until(lambda h: bool(flipped), 60, "the flipped reply")
    v.run_for(20)
    return t


@pytest.mark.parametrize("model", MODELS)
def test_a_flipped_bit_in_a_reading_at_rest_is_never_taken(rig: Rig, model: str) -> None:
    v = at_rest(rig, model)
    t, rest = v.now, v.status.bearing_deg
    sent = len(v.sent())
    flip_and_wait(v)
    shown = {(s.bearing_deg, s.state) for s in v.published(since=t)}
    assert shown == {(rest, MotionState.IDLE)}
    assert v.status.bearing_deg == rest
    assert [e.kind for e in v.errors(since=t)] == [ErrorKind.PROTOCOL]  # junk, once
    query = v.cfg.spec.codec_factory().encode_query()
    assert set(v.sent()[sent:]) == set(query if isinstance(query, list) else [query])


@pytest.mark.parametrize("model", MODELS)
def test_a_move_by_hand_at_rest_is_believed_on_the_reading_after(rig: Rig, model: str) -> None:
    v = at_rest(rig, model)
    t = v.now
    v.manual_rotate(250.0)
    v.run_until(lambda h: h.truth().az_deg == 250.0 and not h.truth().is_moving, 120, "turned")
    v.run_for(10)
    assert v.status.bearing_deg is not None and abs(v.status.bearing_deg - 250.0) <= 1.0
    assert MotionState.MOVING in {s.state for s in v.published(since=t)}
    assert v.errors(since=t) == []


@pytest.mark.parametrize("model", MODELS)
def test_a_flipped_bit_in_the_first_reading_after_a_replug_at_rest_is_never_taken(
    rig: Rig, model: str
) -> None:
    """An attack pass: the first reading back after a replug (or a silence) was believed
    unchecked; one flipped bit in it was published as the bearing at rest, and a nudge then
    turned the rotor some 190 degrees. Where it stood still when its readings were lost, the
    first one back is doubted as any reading at rest is."""
    v = at_rest(rig, model)
    rest = v.status.bearing_deg
    v.link_down()
    v.run_for(2.0)
    t = v.now
    flipped = flip_next_hundreds(v)
    v.link_up()
    v.run_until(lambda h: bool(flipped) and h.status.available, 60, "back, the flipped reply")
    v.run_for(20)
    assert {s.bearing_deg for s in v.published(since=t)} - {None} == {rest}
    assert v.status.bearing_deg == rest and v.state is MotionState.IDLE


def test_a_flipped_elevation_bit_in_the_first_reading_after_a_replug_is_never_taken(
    rig: Rig,
) -> None:
    """A review: the elevation's stand was lost with the port (only the azimuth was kept), so
    EL=045 read as EL=145 was taken at once, and an azimuth-only target then sent W160 145."""
    v = rig("gs232b", settings={"unasked_moves": "follow"})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.aim(Target(150.0, 45.0))
    v.run_until(lambda h: h.state is MotionState.IDLE and h.now > 30, 200, "at 150/45")
    v.run_for(10)
    rest = v.status.elevation_deg
    v.link_down()
    v.run_for(2.0)
    t = v.now
    when: list[float] = []
    tail = bytearray(b"   ")

    def flip(data: bytes, now: float) -> bytes:  # EL=045 reads EL=145 (0x30 -> 0x31)
        out = bytearray()
        for b in data:
            if not when and b == ord("0") and bytes(tail) == b"EL=":
                when.append(now)
                b = ord("1")
            tail[:] = tail[-2:] + bytes([b])
            out.append(b)
        return bytes(out)

    v.to_host = flip
    v.link_up()
    v.run_until(lambda h: bool(when) and h.status.available, 60, "back, the flipped reply")
    v.aim(Target(160.0, None))
    v.run_for(30)
    assert {s.elevation_deg for s in v.published(since=t)} - {None} == {rest}
    assert [w for w in v.sent(since=t) if w.startswith(b"W")] == [b"W160 045\r"]


def test_a_flipped_bit_in_the_first_reading_after_a_silence_at_rest_is_never_taken(
    rig: Rig,
) -> None:
    v = at_rest(rig, "gs232b")
    rest = v.status.bearing_deg
    v.to_host = lambda data, now: b""  # the controller silent: offline
    v.run_until(lambda h: not h.status.available, 60, "offline")
    t = v.now
    flipped = flip_next_hundreds(v)
    v.run_until(lambda h: bool(flipped) and h.status.available, 60, "back, the flipped reply")
    v.run_for(20)
    assert {s.bearing_deg for s in v.published(since=t)} - {None} == {rest}
    assert v.status.bearing_deg == rest


def test_a_move_by_hand_while_unplugged_is_believed_on_the_reading_after(rig: Rig) -> None:
    v = at_rest(rig, "gs232b")
    v.link_down()
    t = v.now
    v.manual_rotate(250.0)
    v.run_until(lambda h: h.truth().az_deg == 250.0 and not h.truth().is_moving, 120, "turned")
    v.link_up()
    v.run_until(lambda h: h.status.available, 60, "back")
    v.run_for(10)
    assert v.status.bearing_deg is not None and abs(v.status.bearing_deg - 250.0) <= 1.0
    assert not any(f.startswith(b"S") for f in v.sent(since=t))  # no stop: nothing to stop


@pytest.mark.parametrize("model", [m for m in MODELS if m != "satel"])  # (silent as it slews)
def test_a_flipped_bit_in_a_reading_while_turning_is_never_published(rig: Rig, model: str) -> None:
    """Rule 9 while the rotor turns: a reading further from the one before than the rotor can
    have turned since (motion.py ``reach_deg``) is asked again at once; the reading after it,
    back on the way, shows it was line noise (before: 33x published for one poll on the way
    from 150 to 100, and a dashboard's history drew the spike)."""
    v = at_rest(rig, model)
    t = v.now
    v.aim(Target(100.0, None))
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg < 140, 60, "turning")
    flipped = flip_next_hundreds(v)  # 13x reads 33x
    v.run_until(lambda h: bool(flipped), 10, "the flipped reply")
    v.run_until(lambda h: h.state is MotionState.IDLE, 60, "at rest")
    shown = [s.bearing_deg for s in v.published(since=t) if s.bearing_deg is not None]
    assert max(shown) <= 155 and abs(v.status.bearing_deg - 100.0) <= 3.0
    assert [e.kind for e in v.errors(since=t)] == [ErrorKind.PROTOCOL]  # junk, once
    assert "while the rotor turned" in v.errors(since=t)[0].message


def test_a_reading_at_rest_said_twice_is_believed(rig: Rig) -> None:
    """A controller recalibrated at its panel (every reading from now on 200 degrees more)
    says its new bearing twice: believed on the second, no junk reported."""
    v = at_rest(rig, "gs232b")
    t = v.now
    v.to_host = lambda data, now: data.replace(b"1", b"3")  # 150 reads 350 from now on
    v.run_for(30)
    assert v.status.bearing_deg == 350.0
    assert v.errors(since=t) == []


def test_readings_at_rest_that_go_on_disagreeing_are_reported_and_polled_as_ever(
    rig: Rig,
) -> None:
    """A failing position sensor (each reading elsewhere): the bearing shown stays the last
    two readings agreed on, the readings are reported, and the line is polled at its idle
    rate, not at once after each."""
    v = at_rest(rig, "gs232b")
    rest, query = v.status.bearing_deg, b"C\r"
    t0 = v.now
    v.run_for(30)
    polls_before = v.sent(since=t0).count(query)
    digits = iter(b"2340" * 1000)  # 150 reads 250, 350, 450 (past 360: a lone misfit), 50...

    def failing(data: bytes, now: float) -> bytes:
        return data.replace(b"1", bytes([next(digits)])) if b"1" in data else data

    v.to_host = failing
    t = v.now
    v.run_for(30)
    assert v.status.bearing_deg == rest and v.status.available
    assert {s.state for s in v.published(since=t)} <= {MotionState.IDLE}
    assert v.sent(since=t).count(query) <= polls_before + 1
    told = [e.message for e in v.errors(since=t)]
    assert any("readings in a row at rest disagree" in m for m in told), told


def test_a_failing_sensor_after_a_replug_leaves_the_rotator_online_where_it_stood(
    rig: Rig,
) -> None:
    """A review: the same failing sensor, first seen after a replug, kept the rotator offline
    (every target refused) for as long as its readings disagreed, where inside a session it
    stays online at the last bearing two readings agreed on. The first reading back, doubted,
    is an answer all the same."""
    v = at_rest(rig, "gs232b")
    rest = v.status.bearing_deg
    v.link_down()
    v.run_for(2.0)
    digits = iter(b"2340" * 1000)  # 150 reads 250, 350, 450 (past 360: a lone misfit), 50...
    v.to_host = lambda data, now: (
        data.replace(b"1", bytes([next(digits)])) if b"1" in data else data
    )
    t = v.now
    v.link_up()
    v.run_for(30)
    assert v.status.available and v.status.bearing_deg == rest
    assert {s.bearing_deg for s in v.published(since=t)} - {None} == {rest}
    # (offline until the port answers; never shown turning)
    assert {s.state for s in v.published(since=t)} <= {MotionState.OFFLINE, MotionState.IDLE}
    told = [e.message for e in v.errors(since=t)]
    assert any("readings in a row at rest disagree" in m for m in told), told


def test_a_stop_lost_at_a_reconnect_stays_owed_when_the_first_reading_back_was_doubted(
    rig: Rig,
) -> None:
    """A review: the first reading back doubted made the controller answering, so the first
    one taken after it was no connection's first, and stops.py rule 3 took it for proof that
    a STOP lost on the line at the reconnect had taken (a lone reading always looks still):
    the port lost again, the stop was owed no more."""
    v = at_rest(rig, "gs232b")  # at rest at 150
    v.link_down()
    v.run_for(1.0)
    v.manual_rotate(300.0)  # it turns while the port is out (a hand at the panel)
    v.run_for(4.0)
    v.stop()  # the operator's STOP while the port is out: owed, the first frame at connect
    v.run_for(0.2)
    assert v.status.stop_owed
    v.drop_writes(b"\rS\r")  # ... and the line loses it (a connection's first: gs232.py rule 6)
    stop_t = v.now
    v.link_up()
    c = v.session.controller
    # the first reading back (~175) is doubted (apart from 150), the one asked at once taken
    v.run_until(lambda h: c.motion.position_deg is not None and c.motion.position_deg > 160, 10)
    v.run_until(lambda h: h.now >= stop_t + STOP_UNSURE_S + 0.01, 5)
    assert v.truth().is_moving  # the stop never arrived
    v.link_down()  # the adapter drops out again
    v.run_for(0.2)
    assert v.status.stop_owed


# -- where the rule's first form did not reach (a cold review) ---------------------------------
FAST = {
    Axis.AZIMUTH: {"az_speed_deg_s": 6.0},
    Axis.ELEVATION: {"az_speed_deg_s": 6.0, "el_speed_deg_s": 2.5, "start_az_deg": 150.0},
}


@contextmanager
def composite_at_rest() -> Iterator[VirtualComposite]:
    """An RT-21 and a GS-232B (its own azimuth at 150) at rest at 200/10."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(200.0, 10.0))
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > 5, 200, "idle")
        v.run_for(10.0)
        assert v.el.truth().az_deg == 150.0
        yield v


def test_a_flipped_bit_in_the_elevation_boxs_own_azimuth_never_turns_that_rotor() -> None:
    """axes.py rule 5: on a composite's elevation box (an az/el GS-232B used for its elevation)
    the session sees the echo of the azimuth it asked for (axes.py rule 2), so rule 9 never
    sees the box's own azimuth; a glitch in it (150 read 350) is never sent back with the next
    elevation target (a review: ``W350 030``, the azimuth rotor nobody asked to turn turned)."""
    with composite_at_rest() as v:
        flipped = flip_next_hundreds(v.el)  # the elevation box's next reply: AZ=150 -> AZ=350
        v.run_until(lambda h: bool(flipped), 30, "the flipped reply")
        v.run_for(0.1)  # the exchange is over, the reading taken (the next poll is 1 s away)
        v.el.to_host = None
        t = v.now
        v.aim(Target(None, 30.0))  # the elevation alone
        v.run_for(60.0)
        sent = [w for w in v.el.sent(since=t) if w.startswith(b"W")]
        assert v.el.truth().az_deg == 150.0, (v.el.truth(), sent)  # its azimuth never turned
        assert sent and all(w.startswith(b"W150 ") for w in sent), sent


def test_a_flipped_bit_in_the_azimuth_boxs_own_elevation_never_turns_that_rotor() -> None:
    """axes.py rule 5 on the azimuth box (an az/el GS-232B used for its azimuth, axes.py rule 1):
    its own elevation read 145 for 45 (one flipped bit) is never sent back with the next
    azimuth target (a review: its elevation rotor went to 145)."""
    boxes = {Axis.AZIMUTH: {"start_el_deg": 45.0}, Axis.ELEVATION: FAST[Axis.AZIMUTH]}
    with VirtualComposite("gs232b", "rt21", emulators=boxes) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(200.0, 10.0))
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > 5, 200, "idle")
        v.run_for(10.0)
        line = bytearray()
        flipped: list[float] = []

        def flip(data: bytes, now: float) -> bytes:  # (the box sends byte by byte)
            line.extend(data)
            if not line.endswith(b"\n"):
                return b""
            whole = bytes(line)
            line.clear()
            if not flipped and b"EL=045" in whole:
                flipped.append(now)
                return whole.replace(b"EL=045", b"EL=145")
            return whole

        v.az.to_host = flip
        v.run_until(lambda h: bool(flipped), 30, "the flipped reply")
        v.run_for(0.1)
        t = v.now
        v.aim(Target(210.0, None))  # the azimuth alone
        v.run_for(60.0)
        sent = [w for w in v.az.sent(since=t) if w.startswith(b"W")]
        assert v.az.truth().el_deg == 45.0, (v.az.truth(), sent)  # its elevation never turned


def test_a_flipped_bit_at_rest_after_a_stop_at_rest_is_never_taken(rig: Rig) -> None:
    """Rule 9 after a STOP at rest, long checked (a review: while a stop was out the doubt was
    off, and a STOP at rest stays out until the next target: hours)."""
    v = at_rest(rig, "gs232b")
    rest = v.status.bearing_deg
    v.stop()
    v.run_for(120.0)  # the stop long checked: the rotor never turned
    shown = {s.bearing_deg for s in v.published(since=flip_and_wait(v))}
    assert shown <= {rest}, shown


def test_a_flipped_bit_after_the_lock_is_released_is_never_taken(rig: Rig) -> None:
    """Rule 9 after tower work: lock ON, then OFF (a review: the lock's stop kept the doubt off
    until the next target)."""
    v = at_rest(rig, "gs232b")
    rest = v.status.bearing_deg
    v.lock(True)
    v.run_for(60.0)
    v.lock(False)
    v.run_for(10.0)
    shown = {s.bearing_deg for s in v.published(since=flip_and_wait(v))}
    assert shown <= {rest}, shown


def test_a_flipped_bit_in_the_brake_window_is_never_taken(rig: Rig) -> None:
    """Rule 9 in a Rotor-EZ's brake window after a move (a review: the doubt was for IDLE only;
    the flipped bit was published as a move and the brake window began again)."""
    v = rig("rotorez")
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.aim(Target(150.0, None))
    v.run_until(lambda h: h.state is MotionState.BRAKING, 200, "braking at 150")
    rest = v.status.bearing_deg
    t = v.now
    flipped = flip_next_hundreds(v)
    v.run_until(lambda h: bool(flipped), 60, "the flipped reply")
    assert v.session.controller.motion.state in (MotionState.BRAKING, MotionState.MOVING)
    v.run_for(20)
    shown = {s.bearing_deg for s in v.published(since=t)}
    assert rest is not None and all(b is not None and abs(b - rest) < 5 for b in shown), shown


@pytest.mark.parametrize("model", MODELS)
def test_a_flipped_bit_at_rest_cut_short_by_a_stop_is_never_taken(rig: Rig, model: str) -> None:
    """Rule 9 for the reading a STOP cuts short (link.py rule 9: taken just before the stop is
    written, controller.py rule 5): doubted too (a review: it went around the doubt, was
    published, and the reading after it was taken for a move after the stop)."""
    v = at_rest(rig, model)
    rest = v.status.bearing_deg
    t = v.now
    flipped = flip_next_hundreds(v)
    v.run_until(lambda h: bool(flipped), 60, "the flipped reply")
    link = v.session.controller.link
    assert link is not None
    v.run_until(lambda h: link._held is not None, 1, "the reply whole, held for its quiet time")
    v.stop()
    v.run_for(20)
    shown = {s.bearing_deg for s in v.published(since=t)}
    assert shown <= {rest}, shown


def test_a_flipped_bit_in_the_elevation_boxs_own_azimuth_while_it_turns_never_turns_it() -> None:
    """axes.py rule 5 while the elevation turns (a tracking pass sends an elevation every few
    seconds): the box's unused azimuth never turns, so a glitch in it is never sent back."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(200.0, 10.0))
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > 5, 200, "idle")
        v.aim(Target(None, 60.0))  # 20 s of elevation travel at 2.5 degrees a second
        v.run_for(3.0)
        flipped = flip_next_hundreds(v.el)
        v.run_until(lambda h: bool(flipped), 30, "the flipped reply")
        v.run_for(0.1)
        v.el.to_host = None
        t = v.now
        v.aim(Target(None, 40.0))  # a new elevation while it turns
        v.run_for(60.0)
        sent = [w for w in v.el.sent(since=t) if w.startswith(b"W")]
        assert v.el.truth().az_deg == 150.0, (v.el.truth(), sent)  # its azimuth never turned


def test_a_flipped_bit_at_rest_after_a_stall_is_never_taken(rig: Rig) -> None:
    """Rule 9 after a stall (STALLED until the next target; a review: a flipped bit was published,
    and the stall watch stopped the "move" with a false error)."""
    v = at_rest(rig, "gs232b")
    rest = v.status.bearing_deg
    v.jam()
    v.aim(Target(250.0, None))
    v.run_until(lambda h: h.state is MotionState.STALLED, 120, "stalled")
    v.run_for(120.0)  # the rotor still, for minutes
    assert v.state is MotionState.STALLED
    t = v.now
    shown = {s.bearing_deg for s in v.published(since=flip_and_wait(v))}
    told = [e.message for e in v.errors(since=t)]
    assert shown <= {rest} and not any("turning" in m for m in told), (shown, told)


def test_a_target_during_a_front_panel_move_is_not_sent_on_a_doubted_reading(rig: Rig) -> None:
    """Rule 9 with targets.py rule 7: a doubted reading is no fresh reading; a target that comes
    while a move at the panel is being confirmed waits for the answer, and the Rotor-EZ is
    stopped first (a review: the target went out at once into the move, was ignored, and a
    stall was reported 10 s later)."""
    from bridge.emulators.rotorez_models import Outcome

    query = b"AI1;"
    v = rig("rotorez", settings={"idle_poll_interval_s": 2.0})
    v.run_until_state(MotionState.IDLE, 30)
    v.run_for(10.0)
    n = len(v.frames(Outcome.QUERY))
    v.run_until(lambda h: len(h.frames(Outcome.QUERY)) > n, 3, "a poll")
    v.run_for(0.05)  # its answer
    v.manual_rotate(100)  # begun after the last poll: the bridge still believes "idle"
    v.run_for(1.2)  # 7 degrees at 6 degrees a second, before the next idle poll
    assert v.state is MotionState.IDLE
    t = v.now
    v.target(200)
    v.run_for(60.0)
    frames = [(f.data, f.outcome) for f in v.frames(since=t)]
    writes = [f for f in frames if f[0] != query]
    stalls = [e.message for e in v.errors(since=t) if "stalled" in e.message]
    # what the user sees: the Rotor-EZ ignored the bearing ("re-target while turning") and
    # stopped where the hand had it, the target never reached, and a false stall reported
    assert abs(v.truth().az_deg - 200.0) < 1.0 and not stalls, (v.truth().az_deg, stalls)
    assert writes[:1] == [(b";", Outcome.STOP)], frames[:4]  # stopped first, as rule 7 has it


# -- a second cold review: a stop cut short on a doubted reading, a lock at start -----------
def test_a_lost_stop_cut_short_on_a_doubted_reading_is_sent_again(rig: Rig) -> None:
    """controller.py rule 9: a rotor taken for at rest is being turned at its panel; the
    idle poll's reply shows it 7 degrees away and an operator's STOP, lost on the line, cuts
    that reading short. The doubted reading is asked again as soon as the stop is out, and the
    next, a few degrees further on, agrees within what the rotor turns between them: the rotor
    is seen turning and the stop is sent again (a review: asked a moving poll later, each
    reading disagreed with the last, the rotor ran on 180 degrees shown at rest)."""
    v = rig(
        "gs232b",
        settings={"moving_poll_interval_s": 1.0, "settle_s": 2.0, "idle_poll_interval_s": 2.0},
    )
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.aim(Target(150.0, None))
    v.run_until(lambda h: h.state is MotionState.IDLE and h.now > 10, 200, "at 150")
    v.run_for(10)
    link = v.session.controller.link
    assert link is not None
    # just after a reading is taken: the next idle poll is ~2 s away
    v.run_until(lambda h: link._held is not None, 5, "a reading held")
    v.run_until(lambda h: link._held is None, 1, "taken")
    rest = v.status.bearing_deg
    v.manual_rotate(330.0)
    v.run_until(lambda h: link._held is not None, 5, "the next idle poll's reading held")
    assert abs(v.truth().az_deg - rest) > 5, v.truth()
    t = v.now
    v.drop_writes(b"S\r")  # the stop lost on the line
    v.stop()
    v.run_for(40.0)
    stops = [w for w in v.sent(since=t) if w == b"S\r"]
    moving_t = [x for x, s in v.statuses if x >= t and s.state is MotionState.MOVING]
    # stops.py rule 2: the stop checked and sent again within stop_resend_s of a reading
    # showing the rotor turning; the rotor must not run on to the panel's bearing
    assert v.truth().az_deg < 250.0, (
        f"the rotor ran on to {v.truth().az_deg:g} after a lost STOP; stops written {stops}; "
        f"first shown moving at {moving_t[:1]} (STOP at {t:.1f}); "
        f"errors={[e.message for e in v.errors(since=t)]}"
    )


def a_move_by_hand_an_hour_later_is_not_stopped(v: VirtualRotator) -> None:
    v.run_for(3600.0)
    t = v.now
    v.manual_rotate(300.0)
    v.run_for(120.0)
    stops = [w for w in v.sent(since=t) if w == b"S\r"]
    told = [e.message for e in v.errors(since=t)]
    assert stops == [] and abs(v.truth().az_deg - 300.0) < 1, (stops, v.truth().az_deg, told)


def test_a_move_by_hand_long_after_a_locked_start_is_not_stopped(rig: Rig) -> None:
    """stops.py rule 2 with session.py rule 11: a session that starts locked writes a stop on
    its first connect, checked while the lock holds; released, a turn made at the panel an
    hour later is the operator's (a review: the bridge stopped it, and again every
    stop_resend_s)."""
    v = rig("gs232b", locked=True)
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.lock(False)
    a_move_by_hand_an_hour_later_is_not_stopped(v)


def test_control_a_move_by_hand_long_after_an_unlocked_start_is_not_stopped(rig: Rig) -> None:
    v = rig("gs232b")
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.run_for(3600.0)
    t = v.now
    v.manual_rotate(300.0)
    v.run_for(120.0)
    stops = [w for w in v.sent(since=t) if w == b"S\r"]
    assert stops == [] and abs(v.truth().az_deg - 300.0) < 1, (stops, v.truth().az_deg)


# -- a third cold review: idle polls far apart, a lock released at once --------------------------
def at_rest_polled(rig: Rig, idle_s: float) -> VirtualRotator:
    v = rig("gs232b", settings={"idle_poll_interval_s": idle_s})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.aim(Target(150.0, None))
    v.run_until(lambda h: h.state is MotionState.IDLE and h.now > 10, 200, "at 150")
    v.run_for(3 * idle_s)
    assert v.status.bearing_deg is not None and 140 <= v.status.bearing_deg < 160
    return v


def test_a_failing_sensor_polled_every_30_s_is_never_believed(rig: Rig) -> None:
    """Rule 9: readings that go on disagreeing leave the bearing shown where the last two
    readings agreed. With idle polls 30 s apart, 2 x 6 deg/s x 30 s = 360 degrees: the third
    garbage reading "agrees" with the second whatever it says, and is taken as a move."""
    v = at_rest_polled(rig, 30.0)
    rest = v.status.bearing_deg
    digits = iter(b"2340" * 1000)  # 150 reads 250, 350, 450 (junk), 50, 250 ...

    def failing(data: bytes, now: float) -> bytes:
        return data.replace(b"1", bytes([next(digits)])) if b"1" in data else data

    v.to_host = failing
    t = v.now
    v.run_for(200.0)
    shown = [(round(s.bearing_deg or -1), s.state.value) for s in v.published(since=t)]
    assert v.status.bearing_deg == rest and {s for _, s in shown} <= {"idle"}, shown


def never_shown_but(v: VirtualRotator, rest: float | None, done: list[float]) -> None:
    """Three noisy readings come, and no bearing but ``rest`` is published meanwhile."""
    t = v.now
    v.run_until(lambda h: len(done) == 3, 120, "three noisy readings")
    v.run_for(5.0)
    shown = [(round(s.bearing_deg or -1), s.state.value) for s in v.published(since=t)]
    assert {b for b, _ in shown} <= {round(rest or -1)}, (done, shown)


def test_two_flipped_bits_in_a_row_then_one_at_the_next_idle_poll(rig: Rig) -> None:
    """A burst of line noise: the reading at rest (150) is read 350, the one asked again at once
    250 (disagreeing: asked at the next idle poll, 30 s on), and that one 50. Three readings, no
    two alike: none is believed (a review: 50 was, within what a rotor turns in 30 s)."""
    v = at_rest_polled(rig, 30.0)
    rest = v.status.bearing_deg
    seq = iter([b"3", b"2", b"0"])
    done: list[float] = []

    def noisy(data: bytes, now: float) -> bytes:
        if b"1" in data and len(done) < 3:
            d = next(seq)
            done.append(now)
            return data.replace(b"1", d, 1)
        return data

    v.to_host = noisy
    never_shown_but(v, rest, done)


def test_a_noise_burst_whose_third_reading_is_near_the_second_is_never_believed(
    rig: Rig,
) -> None:
    """The same burst with the third reading 80 degrees from the second (150 read 350, then
    250, then 170 at the next idle poll): within doubt_deg plus any cap of 90 degrees on the
    turn, so "said twice" though no reading repeated another."""
    v = at_rest_polled(rig, 30.0)
    rest = v.status.bearing_deg
    # each noisy reading: (digit index after "=", byte read instead)
    seq = iter([(0, ord("3")), (0, ord("2")), (1, ord("7"))])
    done: list[float] = []
    pos = [-1]  # digits since the "AZ=" of the reply under way (-1: none)
    last = [0]
    flip: list[tuple[int, int] | None] = [None]

    def noisy(data: bytes, now: float) -> bytes:
        out = bytearray()
        for b in data:
            prev, last[0] = last[0], b
            if b == ord("=") and prev == ord("Z"):
                pos[0] = 0
                flip[0] = next(seq, None) if len(done) < 3 else None
                if flip[0] is not None:
                    done.append(now)
            elif pos[0] >= 0 and chr(b).isdigit():
                if flip[0] is not None and flip[0][0] == pos[0]:
                    b = flip[0][1]
                pos[0] += 1
            else:
                pos[0] = -1
            out.append(b)
        return bytes(out)

    v.to_host = noisy
    never_shown_but(v, rest, done)


def test_a_locked_starts_lost_stop_is_still_checked_when_the_lock_is_released_at_once(
    rig: Rig,
) -> None:
    """session.py rule 11 with stops.py rule 2: the bridge restarts locked (state file) while
    the controller still drives the turn it had (here: driven as at its panel); the stop owed
    on the first connect is lost on the line. The retained lock OFF comes a moment after the
    first reading (the MQTT connection's first look). The check of that stop stays until a
    reading a resend time after it shows the rotor still (a review: released at once, the
    readings that then showed it turning stopped nothing, and it ran on to 330)."""
    v = rig("gs232b", locked=True, connect=False)
    v.manual_rotate(330.0)  # turning when the bridge starts
    v.run_for(2.0)
    v.drop_writes(b"S\r")  # the first connect's stop, lost on the line
    v.link_up()
    v.run_until(lambda h: h.status.available, 10, "the first reading")
    start = v.truth().az_deg
    v.lock(False)  # the retained lock OFF, read a moment later
    v.run_for(120.0)
    stops = [w for w in v.sent() if w == b"S\r"]
    assert abs(v.truth().az_deg - 330.0) > 30, (start, v.truth(), stops)


# -- a fourth cold review: a lost ask, a lock released before the port opens, a replug ------------
def test_a_glitch_whose_asked_again_reply_is_lost_then_a_glitch_30_s_later_is_never_believed(
    rig: Rig,
) -> None:
    """Rule 9: the turn allowance is only for a reading asked again at once, not for one at
    the next idle poll when that ask's reply was lost (a review: the flag stayed, and the
    reading 30 s later was compared within doubt_deg + 90). Noise: 150 read
    170 (tens digit 5 -> 7), the reply asked again lost, 150 read 110 (5 -> 1) at the next
    idle poll: 110 is published, 40 degrees from where the rotor stands."""
    v = at_rest_polled(rig, 30.0)
    rest = v.status.bearing_deg
    assert rest == 150.0
    plan = iter(["flip7", "drop", "flip1"])
    done: list[tuple[float, str]] = []
    line = bytearray()

    def noisy(data: bytes, now: float) -> bytes:  # whole replies (the device sends byte by byte)
        line.extend(data)
        if not line.endswith(b"\n"):
            return b""
        whole = bytes(line)
        line.clear()
        if b"AZ=" not in whole or len(done) >= 3:
            return whole
        what = next(plan)
        done.append((now, what))
        if what == "drop":
            return b""
        return whole.replace(b"AZ=150", b"AZ=170" if what == "flip7" else b"AZ=110")

    v.to_host = noisy
    t = v.now
    v.run_until(lambda h: len(done) == 3, 200, "three faults")
    v.run_for(5.0)
    shown = [(s.bearing_deg, s.state.value) for s in v.published(since=t)]
    assert v.truth().az_deg == 150.0
    assert {b for b, _ in shown} <= {rest}, (done, shown)


def test_a_locked_start_released_before_the_port_opens_lets_a_later_hand_move_be(rig: Rig) -> None:
    """stops.py rule 2: the lock's stop is not checked after the lock is released, also one
    owed when it was released (session.py rule 11: a locked start, the adapter out) and
    written on connect (a review: checked for ever, a turn at the panel an hour later was
    stopped)."""
    v = rig("gs232b", locked=True, connect=False)
    v.run_for(5.0)
    v.lock(False)  # the operator releases the lock while the port is still out
    v.run_for(5.0)
    v.link_up()
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    a_move_by_hand_an_hour_later_is_not_stopped(v)


def test_a_flipped_bit_in_the_first_reading_after_a_replug_never_turns_the_unused_axis() -> None:
    """axes.py rule 5 after a replug: the codec is new at every connect, and a box's first value
    of its unused axis counts once said twice too (a review: one flipped bit in the elevation
    box's first reply, AZ=350 for 150, went out with the next elevation target, and its
    azimuth rotor, which nobody asked to turn, turned 200 degrees)."""
    with composite_at_rest() as v:
        v.el.link_down()
        v.run_for(5.0)
        flipped = flip_next_hundreds(v.el)  # the first reply after the replug: AZ=150 -> 350
        v.el.link_up()
        v.run_until(lambda h: bool(flipped), 30, "the flipped reply")
        v.run_for(0.1)
        v.el.to_host = None
        v.run_until(lambda h: h.status.available, 30, "both boxes answer again")
        t = v.now  # a target as soon as the rotator is online again
        v.aim(Target(None, 30.0))  # the elevation alone
        v.run_for(60.0)
        sent = [w for w in v.el.sent(since=t) if w.startswith(b"W")]
        assert v.el.truth().az_deg == 150.0, (v.el.truth(), sent)


@pytest.mark.parametrize("model", ["gs232b", "easycomm2"])
def test_a_small_glitch_then_a_big_one_are_both_asked_again(rig: Rig, model: str) -> None:
    """Rule 9 doubts any reading the motion machine would take for a move, however small: 150
    read 152 (one flipped bit in the units), then 350 in the next reply (one in the hundreds).
    The first, within 5 degrees, was believed: the motion machine took the rotor for turning,
    rule 9 doubted nothing more, and 350 was published as where it went (a last attack pass;
    an elevation target then would have carried it to the box)."""
    v = at_rest(rig, model)
    rest = v.status.bearing_deg
    assert rest == 150.0
    line, flips = bytearray(), iter([(b"150", b"152"), (b"150", b"350")])
    done: list[float] = []

    def two_flips(data: bytes, now: float) -> bytes:  # whole replies (sent byte by byte)
        line.extend(data)
        if not line.endswith(b"\n"):
            return b""
        whole = bytes(line)
        line.clear()
        if len(done) < 2 and b"150" in whole:
            done.append(now)
            old, new = next(flips)
            return whole.replace(old, new, 1)
        return whole

    v.to_host = two_flips
    t = v.now
    v.run_until(lambda h: len(done) == 2, 30, "two flipped replies")
    v.run_for(20)
    shown = {s.bearing_deg for s in v.published(since=t)}
    assert shown <= {rest} and v.truth().az_deg == 150.0, shown


# -- while turning: an attack pass's cases -------------------------------------------------
def asked_again(monkeypatch: pytest.MonkeyPatch) -> list[tuple[float, float]]:
    """Every reading _doubts_turning did not take at once: (time, azimuth)."""
    seen: list[tuple[float, float]] = []
    orig = C.Controller._doubts_turning

    def spy(self, reply, doubted, now):  # type: ignore[no-untyped-def]
        verdict = orig(self, reply, doubted, now)
        if verdict is not C.Doubt.TAKEN:
            seen.append((round(now, 3), reply.az_deg))
        return verdict

    monkeypatch.setattr(C.Controller, "_doubts_turning", spy)
    return seen


def test_a_true_reading_after_a_bearing_sent_mid_turn_is_not_doubted(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An attack pass: an RC2800 at 12 deg/s polled every 1 s while turning, sent a new bearing
    0.1 s before a poll. The reach counted from the target (10.3 degrees) though the reading it
    was compared with was a whole poll (12 degrees) old: the true reading was asked again, and
    the answer told on R/error as line noise. It counts from that reading's time."""
    doubted = asked_again(monkeypatch)
    v = rig(
        "rc2800",
        settings={
            "moving_poll_interval_s": 1.0,
            "settle_s": 2.0,
            "idle_poll_interval_s": 1.0,
            "unasked_moves": "follow",
        },
        emulator={"az_speed_deg_s": 12.0},
    )
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.run_for(10)
    v.target(100.0)
    v.run_for(2.0)
    poll = math.ceil((v.now + 0.5) / 1.0) * 1.0  # (link.py: polls on the interval's grid)
    v.run_for(poll - 0.1 - v.now)
    t = v.now
    v.target(300.0)  # a new bearing while it turns (a direct-retarget box takes it at once)
    v.run_until(lambda h: h.state is MotionState.IDLE and h.now > t + 5, 120, "arrived")
    told = [e.message for e in v.errors(since=t)]
    assert (doubted, told) == ([], []), (doubted, told)


def test_a_slew_report_of_a_satel_faster_than_configured_is_not_blanked(rig: Rig) -> None:
    """An attack pass: a SatEL (8 deg/s) configured at 2 deg/s; the report after a 180-degree
    slew was beyond the reach, asked again, the bearing published blank meanwhile and the answer
    told as line noise. A silent controller's report after its slew is not doubted."""
    v = rig(
        "satel", settings={"az_speed_deg_s": 2.0, "el_speed_deg_s": 1.0, "unasked_moves": "follow"}
    )
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.run_for(5)
    t = v.now
    v.target(180.0, 10.0)
    v.run_until(lambda h: h.state is MotionState.IDLE and h.now > t + 5, 400, "arrived")
    assert v.truth().az_deg == 180.0
    blank = [round(x, 3) for x, s in v.statuses if x > t and s.bearing_deg is None]
    assert blank == [], blank
    assert v.errors(since=t) == [], [e.message for e in v.errors(since=t)]


@pytest.mark.parametrize("model", ["rot2prog", "gs232b", "easycomm2"])
def test_a_rotor_far_faster_than_its_nominal_speed_is_doubted_once_and_followed(
    rig: Rig, model: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An integration test's SPID turning ten times its nominal speed: the first form of the
    doubt asked again for every reading, took none, called the rotor stalled and stopped it.
    The reading after a doubt is taken, and one not back within reach ends the doubt for the
    turn: one doubt, and the rotor goes where it was sent."""
    doubted = asked_again(monkeypatch)
    fast = {"az_speed_deg_s": 30.0, "el_speed_deg_s": 30.0}
    v = rig(model, emulator=fast, settings={"unasked_moves": "follow"})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.run_for(5)
    t = v.now
    v.aim(Target(200.0, None))
    v.run_until(lambda h: h.state is MotionState.IDLE and h.now > t + 3, 120, "at rest")
    off = (v.truth().az_deg - 200.0 + 180.0) % 360.0 - 180.0  # (a SPID may go to -160)
    assert abs(off) <= 1.0 and v.errors(since=t) == []
    assert len(doubted) <= 1
