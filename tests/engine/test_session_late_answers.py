"""A poll answered after its reply time, on the controllers asked one question at a time that
Easycomm and GS-232 are not (their own files prove theirs): protocols/base.py rule 7.

A loaded host (a USB adapter that hands the bytes over late) had a poll's answer come after its
reply time, with the next poll's answer right behind it. What a user saw: the next poll took the
older answer and its own was told on R/error as bytes that are no valid reply (RT-21, SPID), or
the older answer was published as the newer reading, the rotor shown degrees behind where it
was (RC2800, the Prosistel Combi-Track). Nothing may be told, no bearing published older than
the poll it was taken for, and the rotor still stops where it is and turns to the next target.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from bridge.protocols import REGISTRY
from tests.engine.virtual import Sent, VirtualRotator, settled_at

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING
# model: (its poll's first frame, how late its answer comes: past the reply time)
SPID_STATUS = bytes([0x57, *bytes(10), 0x1F, 0x20])
LATE = {
    "rt21": (b"BI1;", 0.5),
    "rot2prog": (SPID_STATUS, 0.95),
    "rot1prog": (SPID_STATUS, 0.75),
    "md01": (SPID_STATUS, 0.5),
    "prosistel-combi": (b"\x02A?\r\x02B?\r", 0.7),
    "rc2800": (b"A\r", 1.2),
}
STOPPED = ("rt21", "rot2prog", "rot1prog", "md01")  # (the others took no older answer then)
SETTINGS = {
    "idle_poll_interval_s": 0.3,
    "moving_poll_interval_s": 0.1,
    "settle_s": 0.6,
    "stall_timeout_s": 5.0,
    "silence_timeout_s": 4.0,
}


def turning(rig: Rig, model: str) -> tuple[VirtualRotator, list[tuple[float, float]]]:
    """The rotor turning from 10 towards 300, past 30; and where it truly was at each poll
    written from then on (filled in as they go)."""
    speed = {"az_speed_deg_s": 6.0} if model not in ("rot2prog", "rot1prog", "md01") else {}
    v = rig(model, settings=SETTINGS, emulator={"start_az_deg": 10, **speed})
    v.run_until_state(IDLE, 60)
    v.target(300, 0 if v.cfg.spec.has_elevation else None)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 30, 60, "turning")
    written: list[tuple[float, float]] = []

    def record(wire: bytes, now: float) -> bytes:
        if wire == LATE[model][0]:
            written.append((now, v.truth().az_deg))
        return wire

    v.to_device = record
    return v, written


@pytest.mark.parametrize("model", sorted(LATE))
def test_a_polls_late_answer_is_neither_told_nor_taken_over_the_next_polls(
    rig: Rig, model: str
) -> None:
    poll, late_s = LATE[model]
    v, written = turning(rig, model)
    v.run_until(lambda h: h.writes[-1] == Sent(h.now, poll), 5, "a poll just written")
    t = v.now
    v.delay_output(late_s)
    v.run_for(late_s + 1.0)
    assert [at for at, _ in v.received if at > t][:1] == [pytest.approx(t + late_s)]  # (late)
    step = 1.0  # whole degrees at the coarsest
    for at, status in v.statuses:
        if at > t and status.bearing_deg is not None:
            asked = [az for w, az in written if w < at]  # where it was at the last poll
            assert not asked or status.bearing_deg >= asked[-1] - step, (at - t, status)
    assert v.errors() == []


@pytest.mark.parametrize("model", STOPPED)
def test_a_polls_late_answer_around_a_stop_is_told_nowhere(rig: Rig, model: str) -> None:
    poll, late_s = LATE[model]
    v, _ = turning(rig, model)
    t = v.stopped_with_late_answers(poll, late_s)
    v.run_for(2.0)  # (the readings at rest)
    truth = v.truth()
    assert not truth.is_moving and v.status.bearing_deg == pytest.approx(truth.az_deg, abs=1.0)
    v.target(70, 0 if v.cfg.spec.has_elevation else None)
    v.run_until(settled_at(70, 0 if v.cfg.spec.has_elevation else None), 60, "at 70")
    assert v.errors() == [] and all(s.available for s in v.published(since=t))


def test_an_rc2800_always_answering_after_its_reply_time_stays_online_and_turns(
    rig: Rig,
) -> None:
    """rc2800.py rules 2 and 6: a box whose every answer comes after the reply time (a host
    that hands the bytes over 1.2 s late), polled every 2 s: its late lines, before any other
    exchange, are the newest it said, read as its stream. Owed late and dropped, they gave no
    reading at all: the rotator went offline after 8 s and its turn was stopped at 64 of 100."""
    settings = {
        "idle_poll_interval_s": 2.0,
        "moving_poll_interval_s": 2.0,
        "settle_s": 4.5,
        "stall_timeout_s": 20.0,
        "silence_timeout_s": 8.0,
    }
    v = rig("rc2800", settings=settings, emulator={"start_az_deg": 10})
    v.run_until(lambda h: h.status.available, 20, "the controller answers")

    def late(wire: bytes, now: float) -> bytes:
        if wire == b"A\r" and now >= v._delayed_until:
            v.delay_output(1.2)  # (its reply time is 1.0 s)
        return wire

    v.to_device = late
    t = v.now
    v.target(100, 0)
    v.run_for(40.0)
    assert v.errors() == []
    assert all(s.available for s in v.published(since=t))
    assert v.truth().az_deg == pytest.approx(100.0, abs=1.0)
    assert v.status.bearing_deg == pytest.approx(100.0, abs=1.0)


# link.py rule 12: a controller whose every answer comes after its model's reply time (a slow
# USB adapter, a serial server on the network): its poll, and how much later than the reply
# time it answers
ALWAYS_LATE = {
    "rt21": b"BI1;",
    "easycomm3": b"AZ EL\n",
    "rotorcard": b"AI1;",
    "gs232b": b"C2\r",
    "md01": SPID_STATUS,
    "prosistel-combi": b"\x02A?\r\x02B?\r",
}


@pytest.mark.parametrize("model", sorted(ALWAYS_LATE))
def test_a_controller_that_always_answers_late_is_online_and_shown_where_the_rotor_is(
    rig: Rig, model: str
) -> None:
    """Every answer 0.1 s past the reply time. Before: offline at once ('does not answer':
    every answer was told harmless as a late one) or, on a GS-232B, whose next poll went
    right when one was given up, each poll took the answer to the one before: the bearing
    published 5 degrees behind a turning rotor."""
    own_speed = model in ("md01", "rotorcard")  # (their emulators' own: 6 deg/s and less)
    v = rig(
        model,
        settings={"idle_poll_interval_s": 1.0},
        emulator={
            "start_az_deg": 10,
            "processing_delay_s": reply_time_s(model) + 0.1,
            **({} if own_speed else {"az_speed_deg_s": 6.0}),
        },
    )
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online at rest")
    assert v.status.bearing_deg == pytest.approx(10, abs=1.0)
    written: list[tuple[float, float]] = []

    def record(wire: bytes, now: float) -> bytes:
        if wire == ALWAYS_LATE[model]:
            written.append((now, v.truth().az_deg))
        return wire

    v.to_device = record
    el = 0 if v.cfg.spec.has_elevation else None
    t = v.now
    v.target(60, el)
    v.run_until(settled_at(60, el), 120, "at 60")
    step = 1.0  # whole degrees at the coarsest
    for at, status in v.statuses:
        if at > t and status.bearing_deg is not None:
            asked = [az for w, az in written if w < at]  # where it was at the last poll
            assert not asked or status.bearing_deg >= asked[-1] - step, (at - t, status)
    assert v.errors() == [] and all(s.available for s in v.published(since=t))


def reply_time_s(model: str) -> float:
    """The model's reply time."""
    return REGISTRY[model].reply_timeout_s


@pytest.mark.parametrize("late_s", [0.75, 0.9])
def test_a_controller_that_answers_later_than_the_bridge_waits_is_offline_saying_so(
    rig: Rig, late_s: float
) -> None:
    """An RT-21 (reply time 0.3 s) that answers later than twice that, from the start: the
    error says it answers, how late, and what the bridge waits (before: 'does not answer')."""
    v = rig("rt21", emulator={"start_az_deg": 10, "processing_delay_s": late_s})
    v.run_until(lambda h: h.errors("serial"), 10, "the error")
    why = v.errors("serial")[0].message
    assert why.startswith("controller on /dev/ttyVIRTUAL does not answer; it answers, late: ")
    assert f"late: {late_s:.2g}" in why or f"late: {late_s + 0.02:.2g}" in why, why
    assert "the bridge waits 0.3 s for the RT-21 (up to 0.6 s" in why


def test_a_controller_that_goes_slow_mid_session_is_offline_saying_it_answers_late(
    rig: Rig,
) -> None:
    """An RT-21 answering in time, then 0.75 s after each poll: offline as ever, after its
    silence timeout, but the error says it answers, late (before: 'stopped answering' alone,
    which is false)."""
    v = rig("rt21", settings={"silence_timeout_s": 4.0}, emulator={"start_az_deg": 10})
    v.run_until(lambda h: h.status.available and h.state is IDLE, 10, "online at rest")
    v.answer_after(0.75)
    v.run_until(lambda h: h.errors("serial"), 10, "the error")
    why = v.errors("serial")[0].message
    assert why.startswith(
        "controller on /dev/ttyVIRTUAL stopped answering (no valid reply for 4 s); it answers,"
        " late: 0.77 s after a poll"
    ), why


def test_a_controller_that_goes_a_little_slow_mid_turn_stays_online(rig: Rig) -> None:
    """An RT-21 that starts answering 0.45 s after each poll (0.15 s past its reply time)
    halfway through a turn: online throughout, no error, no bearing older than the last poll
    published, and it arrives (before: offline 3 s later, the turn stopped)."""
    v, written = turning(rig, "rt21")
    t = v.now
    v.answer_after(0.45)
    v.run_until(settled_at(300), 120, "at 300")
    for at, status in v.statuses:
        if at > t + 1.0 and status.bearing_deg is not None:  # (from the second poll on)
            asked = [az for w, az in written if w < at]
            assert not asked or status.bearing_deg >= asked[-1] - 1.0, (at - t, status)
    assert v.errors() == [] and all(s.available for s in v.published(since=t))


@pytest.mark.parametrize(("model", "late_s"), [("rt21", 0.585), ("rot2prog", 1.1)])
def test_a_controller_whose_answers_end_just_past_the_longest_wait_stays_online(
    rig: Rig, model: str, late_s: float
) -> None:
    """A controller that starts answering late halfway through a turn: each answer begins
    within twice its reply time (RT-21 0.3 s, Rot2Prog 0.72 s) and is whole just after it
    (link.py rule 12: an answer under way at the wait's end is let finish). Online
    throughout, no error, no bearing older than the last poll published, and it arrives.
    Before: each answer was given up with its last bytes on their way. Those spoiled the next
    poll's answer on the RT-21: told on R/error as bytes that are no valid reply, then offline
    as 'answers only garbled replies (no valid reply for 8 s): a noisy line?', the turn
    stopped at 59 of 300; the Rot2Prog's next poll took them, its bearing a poll behind."""
    v, written = turning(rig, model)
    t = v.now
    v.answer_after(late_s)
    el = 0 if v.cfg.spec.has_elevation else None
    v.run_until(settled_at(300, el), 400, "at 300")
    for at, status in v.statuses:
        if at > t + 1.0 and status.bearing_deg is not None:  # (from the second poll on)
            asked = [az for w, az in written if w < at]
            assert not asked or status.bearing_deg >= asked[-1] - 1.0, (at - t, status)
    assert v.errors() == [] and all(s.available for s in v.published(since=t))


def test_a_stop_to_a_spid_that_answers_late_waits_no_longer_than_twice_its_reply_time(
    rig: Rig,
) -> None:
    """An MD-01's line carries one frame at a time (half duplex): a STOP right after a poll
    waits for the answer under way, which this one sends 0.25 s past its reply time, but
    never longer than twice the reply time from the poll (link.py rule 12's bound); and the
    rotor stops where it is (before: offline from the start, no turn at all)."""
    reply_s = reply_time_s("md01")
    v = rig("md01", settings={"idle_poll_interval_s": 1.0}, emulator={"start_az_deg": 10})
    v.answer_after(reply_s + 0.25)
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online at rest")
    v.target(60, 0)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 15, 60, "turning")
    v.run_until(lambda h: h.writes[-1] == Sent(h.now, SPID_STATUS), 5, "a poll just written")
    t = v.now
    stop = v.cfg.spec.codec_factory().encode_stop()
    v.stop()
    v.run_until(lambda h: any(w.t >= t and w.data == stop for w in h.writes), 5, "the stop")
    sent = next(w.t for w in v.writes if w.t >= t and w.data == stop)
    assert sent - t <= 2 * reply_s
    v.run_until(lambda h: h.state is IDLE and not h.truth().is_moving, 10, "stopped")
    assert v.truth().az_deg < 60 and v.errors() == []
    assert v.status.bearing_deg == pytest.approx(v.truth().az_deg, abs=1.0)


@pytest.mark.parametrize("model", ["rt21", "md01", "easycomm3"])
def test_one_adapter_stall_mid_turn_is_told_nowhere_and_shows_no_older_bearing(
    rig: Rig, model: str
) -> None:
    """A USB adapter that stalls once for 2.5 s mid-turn (under the 3 s silence timeout) and
    then hands over every answer it held at once: each is a late answer to a poll given up,
    told nowhere, and the rotor turns on to its target, online throughout. Before: the
    polls given up in the stall (six or more) owed more lines than the codec counted (four),
    and the answers were told on R/error as 'controller sent 25 bytes that are no valid
    reply' (RT-21; 60 on an MD-01, 65 on an Easycomm)."""
    poll = ALWAYS_LATE[model]
    speed = {} if model == "md01" else {"az_speed_deg_s": 6.0}
    v = rig(model, emulator={"start_az_deg": 10, **speed})
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online at rest")
    el = 0 if v.cfg.spec.has_elevation else None
    v.target(60, el)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 20, 60, "turning")
    written: list[tuple[float, float]] = []

    def record(wire: bytes, now: float) -> bytes:
        if wire == poll:
            written.append((now, v.truth().az_deg))
        return wire

    v.to_device = record
    v.run_until(lambda h: h.writes[-1] == Sent(h.now, poll), 5, "a poll just written")
    t = v.now
    v.delay_output(2.5)
    v.run_until(settled_at(60, el), 120, "at 60")
    assert len([w for w, _ in written if t <= w < t + 2.5]) > 4  # (more than a few given up)
    for at, status in v.statuses:
        if at > t and status.bearing_deg is not None:
            asked = [az for w, az in written if w < at]  # where it was at the last poll
            assert not asked or status.bearing_deg >= asked[-1] - 1.0, (at - t, status)
    assert v.errors() == [] and all(s.available for s in v.published(since=t))
