"""Garblers for ``VirtualRotator.to_host``: what a noisy line does to a box's answers.

Each garbler returns a ``(data, now) -> data`` function that rewrites the position answers on their
way to the host, keeping whatever it has not yet seen whole (a line, a frame) for the next
call. Shared by the review tests of the first-readings doubt (controller.py rule 9) and the
unwatched stop (reviews 100, 103, 107, 111), with their rotor (``limited``, ``turning_down``)
and ``lowest_az``, how far a turn they hid ran.
"""

from __future__ import annotations

import re
from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Garble = Callable[[bytes, float], bytes]
ROT2PROG_FRAME = 12  # 0x57, H1..H4, PH, V1..V4, PV, 0x20 (spid.py rule 3)
STEP_S = 0.1  # a step of virtual time to see the lowest bearing: not a deadline
START_DEG = 150.0  # where the turn at the start begins (reviews 107, 113, 118, 125)
AZ_MIN_DEG = 60.0  # the limit it must be stopped short of
TURNING_S = 0.5  # the turn under way when the bridge starts (virtual time, not a deadline)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)


def limited(
    rig: Callable[..., VirtualRotator], model: str, start_deg: float, az_min_deg: float
) -> VirtualRotator:
    """A ``model`` box at ``start_deg``, ``az_min_deg`` configured, its port not yet open."""
    return rig(
        model,
        emulator={"start_az_deg": start_deg},
        settings={"az_min_deg": az_min_deg},
        connect=False,
    )


def confirmed_at_rest(
    rig: Callable[..., VirtualRotator],
    model: str,
    rest_deg: float,
    az_min_deg: float,
    confirmed_s: float,
) -> VirtualRotator:
    """A ``limited`` box at rest at ``rest_deg``, its port opened and its start's readings
    taken on a clean line for ``confirmed_s`` (virtual time): the at-rest start of reviews 116,
    123 and 126."""
    v = limited(rig, model, rest_deg, az_min_deg)
    v.link_up()
    v.run_for(confirmed_s)
    assert v.status.available and v.status.bearing_deg == rest_deg  # (confirmed, clean line)
    return v


def garbled_at_rest(
    v: VirtualRotator, garble: Garble, online_s: float, count_s: float, settle_s: float
) -> float:
    """``v`` online and at rest (within ``online_s``), a further ``count_s`` there (the start's
    carried turn judged, none: review 105), then its answers through ``garble`` for
    ``settle_s`` (virtual time): when the count that follows starts (reviews 116 and 123)."""
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, online_s, "online")
    v.run_for(count_s)  # (at rest a minute: the start's carried turn judged, none; review 105)
    v.to_host = garble
    v.run_for(settle_s)
    return v.now


def turning_down(v: VirtualRotator, under_way_s: float) -> None:
    """The Easycomm box sent a turn to 5 before the bridge opens its port (a turn it goes on
    with across a restart), under way for ``under_way_s`` (virtual time)."""
    v.device.receive(b"AZ5.0 EL0.0\n", v.now)  # (turning when the bridge starts)
    v.run_for(under_way_s)
    assert v.truth().is_moving


def turning_at_the_start(
    rig: Callable[..., VirtualRotator],
    model: str,
    turn: bytes | None,
    emulator: dict[str, object] | None = None,
) -> VirtualRotator:
    """A ``model`` box at START_DEG, az_min_deg AZ_MIN_DEG, its port not yet open, sent ``turn``
    (or, if None, turned to 5 by a hand at the panel) and under way for TURNING_S (virtual
    time): the turn at the start of reviews 113, 118 and 125 (``emulator``: more settings)."""
    v = rig(
        model,
        emulator={"start_az_deg": START_DEG, **(emulator or {})},
        settings={"az_min_deg": AZ_MIN_DEG},
        connect=False,
    )
    if turn is None:
        v.manual_rotate(5.0)  # (turning when the bridge starts: a hand at the panel)
    else:
        v.device.receive(turn, v.now)  # (turning when the bridge starts)
    v.run_for(TURNING_S)
    assert v.truth().is_moving
    return v


def opened_through(v: VirtualRotator, garble: Garble) -> float:
    """``v``'s port opened with every byte it sends through ``garble``: the time it opened."""
    t = v.now
    v.to_host = garble
    v.link_up()
    return t


def at_half_rate() -> Garble:
    """A box at twice the host's baud rate: every second byte read, as another (its top bit
    set, never a line end)."""
    count = [0]

    def read(data: bytes, now: float) -> bytes:
        out = bytearray()
        for byte in data:
            count[0] += 1
            if count[0] % 2 == 0:
                out.append((byte ^ 0x5A) | 0x80)
        return bytes(out)

    return read


def lowest_az(v: VirtualRotator, until: float, start: float, step_s: float = STEP_S) -> float:
    """The lowest azimuth the rotor truly reached, from ``start``, stepping virtual time by
    ``step_s`` until ``until``."""
    lowest = start
    while v.now < until:
        v.run_for(step_s)
        lowest = min(lowest, v.truth().az_deg)
    return lowest


def stopped_before_the_limit(v: VirtualRotator, garble: Garble) -> None:
    """``v``, turning at the start (``turning_at_the_start``), its port opened with every byte
    through ``garble``: the rotor never went past AZ_MIN_DEG in WATCH_S."""
    t = opened_through(v, garble)
    lowest = lowest_az(v, t + WATCH_S, START_DEG)
    said = [e.message for e in v.errors(since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {START_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stop frames: {len(v.frames('stop', since=t))}; said: {said}"
    )


CONFIRMED_S = 15.0  # the start's readings on a clean line (virtual time, not a deadline)
FIRST_STOP_S = 60.0  # eight readings at the moving rate, with room (virtual time)
HAND_S = 60.0  # the hand's turn, with room (virtual time)


def hand_after_the_unwatched_stop(
    rig: Callable[..., VirtualRotator], rest_deg: float, hand_deg: float
) -> VirtualRotator:
    """An Easycomm II box at ``rest_deg``, its start confirmed on a clean line, then a line
    reading every answer 60 degrees off (by turns up and down) until the unwatched stop, then a
    hand turning it to ``hand_deg`` for HAND_S (its unwatched stops may cut the hand short):
    the at-rest set-up of reviews 123 and 126, the line still bad."""
    v = rig("easycomm2", emulator={"start_az_deg": rest_deg}, connect=False)
    v.link_up()
    v.run_for(CONFIRMED_S)
    assert v.status.available and v.status.bearing_deg == rest_deg  # (confirmed, clean line)
    v.to_host = every_answer_off([60.0, -60.0])
    t0 = v.now
    v.run_until(lambda h: bool(h.frames("stop", since=t0)), FIRST_STOP_S, "the unwatched stop")
    v.manual_rotate(hand_deg)
    v.run_for(HAND_S)  # (its unwatched stops may cut the hand short: it rests anyway)
    return v


def easycomm_lines(rewrite: Callable[[bytes], bytes]) -> Garble:
    """Each whole answer line (up to ``\\n``) through ``rewrite``; a part line held back."""
    line = bytearray()

    def garble(data: bytes, now: float) -> bytes:
        line.extend(data)
        out = b""
        while b"\n" in line:
            cut = line.index(b"\n") + 1
            whole = bytes(line[:cut])
            del line[:cut]
            out += rewrite(whole)
        return out

    return garble


def every_answer_off(offsets: list[float]) -> Garble:
    """Each answer line's azimuth reaches the host off by the next of ``offsets``, in turn."""
    count = [0]

    def rewrite(whole: bytes) -> bytes:
        found = re.search(rb"AZ(\d+\.\d)", whole)
        if found:
            off = offsets[count[0] % len(offsets)]
            count[0] += 1
            said = f"AZ{float(found.group(1)) + off:.1f}".encode()
            whole = whole[: found.start()] + said + whole[found.end() :]
        return whole

    return easycomm_lines(rewrite)


def first_answers_one_bit_off(flips: list[bytes]) -> Garble:
    """The box's first ``len(flips)`` answer lines with a bearing of 100 to 199 reach the host
    with its hundreds digit as the next of ``flips``; everything else as sent."""
    left = list(flips)

    def rewrite(whole: bytes) -> bytes:
        found = re.search(rb"AZ1\d\d\.\d", whole)
        if found and left:
            at = found.start() + 2
            whole = whole[:at] + left.pop(0) + whole[at + 1 :]
        return whole

    return easycomm_lines(rewrite)


def first_turning_answer_one_bit_off(rest: str) -> Garble:
    """The first answer line whose azimuth is not ``rest`` (the rotor turned) reaches the host
    with the hundreds digit of that azimuth read ``3`` for ``1``; everything else as sent."""
    done = [False]

    def rewrite(whole: bytes) -> bytes:
        found = re.search(rb"AZ(1\d\d\.\d)", whole)
        if found and not done[0] and found.group(1).decode() != rest:
            done[0] = True
            at = found.start() + 2
            whole = whole[:at] + b"3" + whole[at + 1 :]
        return whole

    return easycomm_lines(rewrite)


def every_rotorez_answer_off(offsets: list[float]) -> Garble:
    """Each ``;ddd`` azimuth answer reaches the host off by the next of ``offsets``, in turn."""
    held = bytearray()
    count = [0]

    def garble(data: bytes, now: float) -> bytes:
        held.extend(data)
        out = b""
        while (found := re.search(rb";(\d{3})", held)) is not None:
            off = offsets[count[0] % len(offsets)]
            count[0] += 1
            said = f";{round(float(found.group(1)) + off) % 360:03d}".encode()
            out += bytes(held[: found.start()]) + said
            del held[: found.end()]
        if b";" not in held:  # (no answer begun: the rest as sent)
            out, held[:] = out + bytes(held), b""
        return out

    return garble


def _rot2prog_frames(offsets: list[float], *, for_good: bool) -> Garble:
    buf = bytearray()
    count = [0]

    def garble(data: bytes, now: float) -> bytes:
        buf.extend(data)
        out = b""
        while len(buf) >= ROT2PROG_FRAME:
            if buf[0] != 0x57:
                out += bytes(buf[:1])
                del buf[:1]
                continue
            frame = bytearray(buf[:ROT2PROG_FRAME])
            del buf[:ROT2PROG_FRAME]
            if frame[-1] == 0x20 and (for_good or count[0] < len(offsets)):
                tenths = frame[1] * 1000 + frame[2] * 100 + frame[3] * 10 + frame[4]
                tenths += round(offsets[count[0] % len(offsets)] * 10)
                count[0] += 1
                frame[1:5] = bytes(
                    [tenths // 1000, tenths // 100 % 10, tenths // 10 % 10, tenths % 10]
                )
            out += bytes(frame)
        return out

    return garble


def frames_off(offsets: list[float]) -> Garble:
    """Each Rot2Prog position frame's azimuth reaches the host off by the next of ``offsets``,
    in turn (the raw digits rewritten: tenths of a degree), then as sent."""
    return _rot2prog_frames(offsets, for_good=False)


def every_frame_off(offsets: list[float]) -> Garble:
    """Each Rot2Prog position frame's azimuth reaches the host off by the next of ``offsets``,
    in turn, for good (the raw digits rewritten: tenths of a degree)."""
    return _rot2prog_frames(offsets, for_good=True)


def rc2800_drifting_from(since: float, every_s: float, step_deg: float = 0.1) -> Garble:
    """An RC2800's lines as they reach the host, each bearing ``step_deg`` more every
    ``every_s`` since ``since`` (a line goes whole at its CR, when the box's last byte of it
    would): a pot read drifting (reviews 110 and 115)."""
    line = bytearray()

    def drift(data: bytes, now: float) -> bytes:
        line.extend(data)
        if not data.endswith(b"\r"):
            return b""
        whole = bytes(line)
        line.clear()
        counts = int((now - since) // every_s)
        return re.sub(
            rb"P=\s*([0-9.]+)",
            lambda m: b"P=%5.1f" % (float(m.group(1)) + step_deg * counts),
            whole,
            count=1,
        )

    return drift


BURST_TARGET_DEG = 300.0  # the turn a burst comes in (reviews 129, 136, 140): to here ...
BURST_SETTLE_S = 60.0  # ... once the first readings are taken, at rest (virtual time)
BURST_TURNING_S = 10.0  # ... and well under way, watched (virtual time, not a deadline)


def turning_for_a_burst(v: VirtualRotator) -> float:
    """``v`` settled at rest, then turning to BURST_TARGET_DEG for BURST_TURNING_S (virtual
    time): when the burst (reviews 129, 136, 140) begins."""
    v.run_until_state(MotionState.IDLE, BURST_SETTLE_S)
    v.target(BURST_TARGET_DEG)
    v.run_for(BURST_TURNING_S)
    assert v.truth().is_moving
    return v.now


def reached_through_the_burst(v: VirtualRotator, t: float) -> None:
    """The turn went on through the burst begun at ``t``: nothing said of the controller's
    answers, no stop written, the rotor at its target."""
    said = [e.message for e in v.errors(since=t) if "answer" in e.message]
    assert said == [], said
    assert not v.frames("stop", since=t)
    assert v.truth().az_deg == pytest.approx(BURST_TARGET_DEG, abs=1.0)
