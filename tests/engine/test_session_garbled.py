"""A garbled answer (session/link.py rule 11, controller.py rule 2): the controller answered, so
it is not silent, but nothing of it is a reading; it is asked again at once, once. A line that
gives only garbage goes offline after two silence timeouts, one that gives nothing after one.
(An attack pass: 0.3 % of bytes flipped took a SatEL offline 5-12 times in 20 minutes.)"""

from __future__ import annotations

import os
import re
import select
from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from bridge.protocols.base import JunkReply
from bridge.protocols.gs232 import MODELS as GS232
from bridge.session.controller import TURN_SILENCE_LEAST_S
from bridge.session.link import JUNK_QUIET_S, Link
from bridge.settings.defaults import DEFAULT_SILENCE_TIMEOUT_S
from tests.engine.test_lines import polled, worker_on_a_pty
from tests.engine.virtual import VirtualRotator
from tests.support import wait_until
from tests.support.rig import FAST_BRIDGE
from tests.support.waiting import slow

Rig = Callable[..., VirtualRotator]
IDLE = MotionState.IDLE
REPORT = (  # a SatEL's status report at rest (satel.py), 165 bytes
    b"Motion ENABLED\r\nMode 0 - azimuth break at NORTH\r\nTime: 2025/06/15 15:06:51\r\n"
    b"Azimuth = 100     Absolute = 100\r\nElevation = 000\r\n\r\n"
    b"Number of stored positions: 00\r\n\r\n\r\n"
)


def garble_lines(
    v: VirtualRotator, label: bytes, garbled: bytes, count: int, end: bytes = b"\n"
) -> list[float]:
    """The next ``count`` reply lines that hold ``label`` reach the host with it as ``garbled``
    (lines handed on whole: the device sends byte by byte); the list gets when each came."""
    when: list[float] = []
    line = bytearray()

    def garble(data: bytes, now: float) -> bytes:
        line.extend(data)
        if not line.endswith(end):
            return b""
        whole = bytes(line)
        line.clear()
        if label in whole and len(when) < count:
            when.append(now)
            return whole.replace(label, garbled)
        return whole

    v.to_host = garble
    return when


def turning(v: VirtualRotator, az: float, after_s: float = 2.0) -> VirtualRotator:
    """``v`` online and at rest, sent ``az``, and turning ``after_s`` seconds since it began."""
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.target(az)
    v.run_until(lambda h: h.state is MotionState.MOVING, 5, "moving")
    v.run_for(after_s)
    return v


def test_two_garbled_satel_reports_in_a_row_keep_it_online_and_are_asked_again(
    rig: Rig,
) -> None:
    """Two reports in a row garbled in their azimuth line: the first is asked again at once (a
    ``z`` right after it), the second waits for the next poll; the SatEL never goes offline, and
    the bearing shown is never anything but where the rotor is."""
    v = rig("satel")
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.run_for(10)
    rest = v.status.bearing_deg
    t = v.now
    garbled = garble_lines(v, b"Azimuth = ", b"Azimu\xf4h = ", 2)
    v.run_until(lambda h: len(garbled) == 2, 30, "two garbled reports")
    v.run_for(30)

    assert all(s.available for s in v.published(since=t))  # (retained availability)
    assert v.errors("serial", since=t) == []
    asked = [w.t for w in v.writes if w.data == b"z" and w.t > garbled[0]]
    assert asked[0] - garbled[0] < 0.2  # asked again at once: not after the reply timeout (2 s)
    assert garbled[1] > asked[0]  # (the second is that re-poll's answer)
    assert [w.t for w in v.writes if garbled[1] < w.t < garbled[1] + 3] == []  # not again
    assert {s.bearing_deg for s in v.published(since=t)} <= {rest} and v.truth().az_deg == rest


def readable(fd: int) -> bool:
    return bool(select.select([fd], [], [], 0)[0])


def report_whole_at(v: VirtualRotator, after: float) -> float:
    """When the first report whose bytes began after ``after`` had come whole (its last bytes:
    the next report's come more than JUNK_QUIET_S later)."""
    times = [t for t, _ in v.received if t > after]
    end = times[0]
    for t in times[1:]:
        if t - end > JUNK_QUIET_S:
            break
        end = t
    return end


def test_a_satel_report_garbled_in_its_second_line_is_asked_again_only_once_it_is_whole(
    rig: Rig,
) -> None:
    """A report garbled in its Mode line: the codec is owed no more from there (satel.py rule
    5), and the good lines after it make no junk; the re-poll goes once no byte has come for
    JUNK_QUIET_S (link.py rule 11), not that long after the garbled line, when ~80 bytes of the
    report were still on the half-duplex line (a review: the ``z`` at +50 ms, the report
    whole at +121 ms)."""
    v = rig("satel")
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.run_for(10)
    garbled = garble_lines(v, b"Mode ", b"Mo\xe4e ", 1)
    v.run_until(lambda h: len(garbled) == 1, 30, "a garbled report")
    v.run_for(3)

    whole = report_whole_at(v, garbled[0] - 0.1)
    [repoll, *_] = [w.t for w in v.writes if w.t > garbled[0]]
    assert whole + JUNK_QUIET_S <= repoll < whole + JUNK_QUIET_S + 0.01, (repoll, whole)


def test_a_small_target_right_after_a_garbled_satel_report_is_not_ended_by_a_stale_report(
    rig: Rig,
) -> None:
    """The same, and a target a step on (satel.py rule 7) comes while the re-poll's report is on
    its way: the
    point waits for that report and the after-move report ends the slew; nothing goes into the
    slewing SatEL (a review: the garbled report's tail closed the re-poll's exchange, answers
    were paired one off, the re-poll's report, from before the point but within
    SLEW_END_TOLERANCE_DEG, ended the slew and the next ``z`` went into it: corrupted)."""
    v = rig("satel", emulator={"start_az_deg": 100, "corrupt_on_misuse": True})
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.run_for(10)
    garbled = garble_lines(v, b"Mode ", b"Mo\xe4e ", 1)
    v.run_until(lambda h: len(garbled) == 1, 30, "a garbled report")
    v.run_for(0.2)  # the re-poll's report under way
    v.target(110.0, 0.0)
    v.run_for(10)

    assert v.frames("misuse: input while slewing") == []
    assert not v.truth().corrupted and v.truth().az_deg == 110.0
    assert v.status.bearing_deg == 110.0 and v.state is IDLE


def test_a_garbled_satel_report_whose_rest_waits_in_the_port_is_read_before_the_repoll() -> None:
    """worker.py rule 2 with link.py rules 7 and 11: a SatEL late with its report, garbled in
    its Mode line; the hold's end finds its first two lines, the hold starts again for the
    rest (116 bytes, 121 ms), which comes into the port meanwhile. The re-poll is written only
    once the rest has been read and the line was quiet JUNK_QUIET_S after it, never during the
    hold with the rest unread (the junk's quiet time alone ends at +50 ms)."""
    with worker_on_a_pty("satel", FAST_BRIDGE) as (worker, master, _box):
        now = polled(worker, master, 100.0, b"z")  # the connect's (s ? t g z)
        os.write(master, b"SatEL\r\n" + REPORT)
        wait_until(lambda: readable(worker._fd), slow(5), "the report in the port")
        worker.guarded(worker.serve, now + 0.2, {worker._fd})
        # a connection's first reading is believed when the next agrees (controller.py rule 9):
        # the report settles, and the SatEL is asked again at once
        now = polled(worker, master, now + 0.3, b"z")
        os.write(master, REPORT)
        wait_until(lambda: readable(worker._fd), slow(5), "the second report in the port")
        worker.guarded(worker.serve, now + 0.2, {worker._fd})
        now = polled(worker, master, now + 0.3, b"z")  # a poll, its report held (rule 7)
        assert worker.status.available
        head, rest = REPORT.replace(b"Mode ", b"Mo\xe4e ").split(b"Time", 1)
        os.write(master, head)
        wait_until(lambda: readable(worker._fd), slow(5), "the first lines in the port")
        now = worker.wants(now)[1]
        worker.guarded(worker.serve, now, set())  # the hold's end: the first lines read
        assert not readable(worker._fd) and worker.session.hold_reads_until() > now + 0.1
        os.write(master, b"Time" + rest)
        wait_until(lambda: readable(worker._fd), slow(5), "the rest in the port")
        read_t, written = None, b""
        while not written:
            now = worker.wants(now)[1]
            worker.guarded(worker.serve, now, set())
            if read_t is None and not readable(worker._fd):
                read_t = now
            while readable(master):
                written += os.read(master, 64)
        assert written == b"z" and read_t is not None
        assert read_t + JUNK_QUIET_S <= now < read_t + JUNK_QUIET_S + 0.01, (now, read_t)


def test_a_line_that_gives_only_garbage_goes_offline_after_two_silence_timeouts(
    rig: Rig,
) -> None:
    """Every answer garbled: online for two silence timeouts (3 s each here) without a valid
    reply, then offline with words that say so, never asked back to back; a line that gives
    nothing at all still goes offline after one silence timeout."""
    v = rig("gs232b")
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.run_for(5)
    last_valid = max(t for t, _ in v.received)
    v.to_host = lambda data, now: data.replace(b"=", b"?")  # every reply garbled from now on
    t = v.now
    v.run_until(lambda h: not h.status.available, 30, "offline")
    off = v.now - last_valid
    assert 6.0 <= off < 6.0 + 1.0 + 1.0, off  # two timeouts, an idle poll and a reply time
    [why] = v.errors("serial", since=t)
    assert "only garbled replies" in why.message and "6 s" in why.message
    polls = [w.t for w in v.writes if w.t >= t]
    assert len(polls) <= 2 * (v.now - t) + 2  # an idle poll a second, one re-poll each at most

    v.to_host = None  # the line heals: online again
    v.run_until(lambda h: h.status.available, 10, "online again")
    v.run_for(5)
    last_valid = max(t for t, _ in v.received)
    v.set_silent(True)  # now nothing comes at all
    t = v.now
    v.run_until(lambda h: not h.status.available, 30, "offline")
    off = v.now - last_valid
    assert 3.0 <= off < 3.0 + 1.0 + 1.0, off  # one timeout (and a poll's answer owed)
    [why] = v.errors("serial", since=t)
    assert "stopped answering (no valid reply for 3 s)" in why.message


def test_a_controller_gone_to_garbage_mid_turn_goes_offline_before_a_stall_is_called(
    rig: Rig,
) -> None:
    """silence_timeout_s 6 (longer than the idle poll), stall_timeout_s 10 (its default): a
    GS-232B turning to a target whose every reply is garbled from then on goes offline with
    words that say so before the motion machine, fed no reading, can call the turn stalled
    (controller.py rule 2: a review found it online for 12 s, and a "stalled" error at 10 s
    that blamed the brake, tracking ended as stalled)."""
    v = rig("gs232b", settings={"silence_timeout_s": 6.0})
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.run_for(5)
    v.target(350.0)
    v.run_until(lambda h: h.state is MotionState.MOVING, 5, "moving")
    v.run_for(1)
    last_valid, t = max(t for t, _ in v.received), v.now
    v.to_host = lambda data, now: data.replace(b"=", b"?")  # every reply garbled from now on
    v.run_for(15)

    assert v.errors("stalled", since=t) == []
    assert MotionState.STALLED not in {s.state for s in v.published(since=t)}
    [(off, why)] = [(at, e) for at, e in v.events if at >= t and e.kind == "serial"]
    assert "only garbled replies" in why.message and v.state is MotionState.OFFLINE
    assert off - last_valid < 10.0, off - last_valid


def test_a_turn_by_hand_whose_reading_asked_again_is_garbled_is_followed(rig: Rig) -> None:
    """An RC2800 at rest turned by hand: its first moving reading is asked again at once
    (controller.py rule 9), and that answer comes garbled. It is asked again at once, and that
    reading, as one asked at once, is believed: the turn is shown while it goes on (it was asked
    at the idle polls instead, each reading a second on disagreeing with the one before: the
    bearing stale for the whole turn). The rotor turns 12 deg/s, the bridge told 6: readings at
    the idle rate never agree within 5 degrees while it turns. Its owner turns it at the panel
    and lets such turns be (the model stops them by default: rc2800.py rule 8)."""
    fast = {"az_speed_deg_s": 12.0, "el_speed_deg_s": 3.0, "start_az_deg": 100}
    v = rig("rc2800", emulator=fast, settings={"az_speed_deg_s": 6.0, "unasked_moves": "follow"})
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.run_for(10)
    assert v.status.bearing_deg == 100.0
    v.manual_rotate(250.0)
    moved: list[float] = []
    line = bytearray()

    def garble_the_ask(data: bytes, now: float) -> bytes:  # the azimuth line after the first
        line.extend(data)  # that shows the turn (the one asked again)
        if not line.endswith(b"\r"):
            return b""
        whole = bytes(line)
        line.clear()
        if whole.startswith(b"A P=") and float(whole[4:].split()[0]) > 101:
            moved.append(now)
            if len(moved) == 2:
                return whole.replace(b"A P=", b"A Q=")
        return whole

    v.to_host = garble_the_ask
    v.run_until(lambda h: len(moved) >= 2, 10, "the ask garbled")
    t = v.now
    v.run_for(4)
    assert v.truth().is_moving  # still turning, and seen to
    assert MotionState.MOVING in {s.state for s in v.published(since=t)}
    shown = v.status.bearing_deg
    assert shown is not None and abs(shown - v.truth().az_deg) < 12.0, (shown, v.truth())


def test_a_line_whose_every_answer_has_noise_in_front_is_asked_again_once_a_poll(rig: Rig) -> None:
    """One noise byte before every GS-232B answer: each reading is not trusted (gs232.py, an
    UNTRUSTED reply) and asked again at once, once (link.py rule 11): an idle poll a second
    and its re-poll, before and after it goes offline for want of a valid reply (a review: it
    was asked again at once without end, 436 polls in 10 s)."""
    v = rig("gs232b")
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.run_for(5)
    rest, t = v.status.bearing_deg, v.now
    v.to_host = lambda data, now: (b"#" + data) if data.startswith(b"A") else data
    v.run_for(10)

    polls = [w.t for w in v.writes if w.t > t]
    assert len(polls) <= 2 * 10 + 2
    assert polls[1] - polls[0] < 0.05  # (asked again at once)
    [why] = v.errors("serial", since=t)
    assert "only garbled replies" in why.message
    assert {s.bearing_deg for s in v.published(since=t)} <= {rest, None}  # (no reading)


def test_a_target_that_waits_for_a_fresh_reading_on_a_noisy_line_is_asked_for_at_a_poll_rate(
    rig: Rig,
) -> None:
    """One noise byte before every Rotor-EZ answer, and a target that waits for a fresh reading
    (targets.py rule 7): it asks at once only while the poll's right to a re-poll holds, then
    at the moving rate (link.py rule 11; a second review: 107 polls in 2 s, every step)."""
    v = rig("rotorez")
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.run_for(5)
    v.to_host = lambda data, now: (b"#" + data) if data.startswith(b";") else data
    v.run_for(1.5)  # (the last valid reading is stale now)
    t = v.now
    v.target(200.0)
    v.run_for(2)

    polls = [w.t for w in v.writes if w.t > t and w.data == b"AI1;"]
    assert 2 <= len(polls) <= 2 * 2 / 0.2 + 2, len(polls)  # a moving poll and its re-poll
    assert not v.truth().is_moving  # (no move: no fresh reading came)


def test_garbage_mid_turn_of_a_slow_rotor_goes_offline_before_a_stall_is_called(
    rig: Rig,
) -> None:
    """A slow rotor (1 deg/s, noise_deg 5, the default silence 3 s) whose replies go to garbage
    just before its next movement the motion machine would see: the stall counts from that
    last movement, seconds before the last valid reply, and the controller goes offline
    before it (controller.py rule 2; a second review: "stalled" at 5.4 s, offline at 6.2)."""
    v = rig(
        "gs232b",
        emulator={"az_speed_deg_s": 1.0, "el_speed_deg_s": 1.0},
        settings={"az_speed_deg_s": 1.0, "el_speed_deg_s": 1.0, "noise_deg": 5.0},
    )
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.run_for(5)
    v.target(90.0)
    v.run_until(lambda h: h.state is MotionState.MOVING, 10, "moving")
    v.run_for(2)
    motion = lambda: v.session.controller.motion  # noqa: E731
    v.run_until(lambda h: abs(motion().position_deg - motion().anchor_deg) >= 4.6, 10, "a step")
    t = v.now
    v.to_host = lambda data, now: data.replace(b"=", b"?")  # every reply garbled from now on
    v.run_for(15)

    assert v.errors("stalled", since=t) == []
    assert MotionState.STALLED not in {s.state for s in v.published(since=t)}
    [why] = v.errors("serial", since=t)
    assert "only garbled replies" in why.message and v.state is MotionState.OFFLINE


def garbled_answer(link: Link, now: float) -> bool:
    """A GS-232B's answer to the poll just written comes garbled at ``now`` (read as the
    controller reads it, controller.py), and the exchange is given up at its deadline (the
    codec still awaits the reply): whether it is asked again at once."""
    [junk] = link.codec.feed(b"AZ?065  EL?000\r")
    assert isinstance(junk, JunkReply)
    link.got_bytes(len(junk.data), now)
    link.add_junk(junk.data, now)
    link.garbles(junk, now)
    assert link.end_garbled(now + 0.5) is None and link.reply_overdue(now + 1.0)
    return link.give_up_reply(now + 1.0)


def test_a_target_written_before_the_repoll_leaves_the_poll_after_it_its_own_repoll() -> None:
    """link.py rule 11: a garbled answer's re-poll is due, and a target takes the line first;
    the poll after the target is a poll of its own: its answer, garbled too, is asked again at
    once (a review: it was counted as the re-poll, its garbled answer left to the next poll)."""
    spec = GS232["gs232b"]
    link = Link(spec.codec_factory(), spec, 0.0, spec.baud)
    assert link.poll(10.0, 1.0) and link.output() == [b"C2\r"]
    assert garbled_answer(link, 10.02) is True  # asked again at once
    link.send(link.codec.encode_target(100.0), 11.02)
    assert link.output() == [b"W100 000\r"]
    assert link.poll(11.1, 0.2) and link.output() == [b"C2\r"]
    assert garbled_answer(link, 11.12) is True
    assert link.poll(12.12, 0.2) and link.output() == [b"C2\r"]  # the re-poll, at once
    assert garbled_answer(link, 12.14) is False  # (its own garbled answer: the next poll)


def test_an_rc2800_whose_every_elevation_answer_is_garbled_is_not_polled_back_to_back(
    rig: Rig,
) -> None:
    """An RC2800's poll is two frames, an answer each (link.py rule 10): its azimuth valid,
    its elevation always garbled. A valid answer gives a poll its re-poll back only when it
    ends the exchange (link.py rule 11): the azimuth's, in the middle of it, does not, or
    every re-poll would earn the next one."""
    v = rig("rc2800", emulator={"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0})
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.run_for(5)
    t = v.now
    garbled = garble_lines(v, b"E P=", b"E ?=", 1000, end=b"\r")
    v.run_for(10)

    polls = [w.t for w in v.writes if w.t > t and w.data.startswith(b"A")]
    assert len(garbled) >= 10  # (every elevation answer)
    assert len(polls) <= 2 * 10 + 2, len(polls)  # an idle poll a second, one re-poll each


def test_a_controller_that_never_gave_a_valid_reply_but_garbled_ones_is_said_to(
    rig: Rig,
) -> None:
    """Every reply garbled from the first (what the wrong baud rate looks like): the complaint
    says it answers garbled, pointing at the line's settings, not that it does not answer (a
    cold review); one that answers nothing still does not answer."""
    v = rig("gs232b")
    v.to_host = lambda data, now: data.replace(b"=", b"?")
    v.run_until(lambda h: h.errors("serial"), 30, "the complaint")
    [why] = v.errors("serial")
    assert "answers only garbled replies" in why.message and "baud" in why.message
    assert not v.status.available

    quiet = rig("gs232b")
    quiet.set_silent(True)
    quiet.run_until(lambda h: h.errors("serial"), 30, "the complaint")
    assert "does not answer" in quiet.errors("serial")[0].message


def test_a_rot2prog_gone_silent_mid_turn_goes_offline_before_a_stall_is_called(
    rig: Rig,
) -> None:
    """A Rot2Prog at its 600 baud (idle-polled every 9.3 s: silence_timeout_s 19.4 by default)
    that goes silent while it turns to a target, jammed, its replies lost but still hearing:
    offline, with words that say so, before the motion machine, fed no reading, could call the
    turn stalled; and stopped, as the stall stopped it (controller.py rule 2: it was called
    "stalled" at 10 s, an error that blamed the brake, and rotor health counted a stall; a
    review: offline with no stop, the motor drove on against the jam)."""
    v = rig("rot2prog")
    assert v.cfg.silence_timeout_s > v.cfg.motion.stall_timeout_s  # (the case: its defaults)
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    v.target(200.0)
    v.run_until(lambda h: h.state is MotionState.MOVING, 5, "moving")
    v.run_for(2)
    t = v.now
    v.set_silent(True)
    v.jam()
    v.run_for(25)

    assert v.errors("stalled", since=t) == []
    assert MotionState.STALLED not in {s.state for s in v.published(since=t)}
    [(off, why)] = [(at, e) for at, e in v.events if at >= t and e.kind == "serial"]
    assert 5.0 <= off - t < 10.0, off - t  # half the stall timeout at least, and before it
    said = re.search(r"stopped answering \(no valid reply for ([0-9.]+) s\)", why.message)
    assert said is not None and off - t - 0.05 <= float(said[1]) <= off - t + 0.6  # (a reply
    # cut short by the silence: the last valid one came a poll before it)
    assert "; a stop sent, in case it still hears" in why.message
    assert not v.truth().is_moving  # (the stop reached the box: it hears)
    assert v.state is MotionState.OFFLINE
    assert {s.health.stalls for s in v.published() if s.health is not None} == {0}  # (1 was)


def test_a_jammed_rotor_whose_controller_then_falls_silent_is_still_called_stalled(
    rig: Rig,
) -> None:
    """Readings that showed no progress for 6 s, then silence: the stall is told by them, not
    an offline (controller.py rule 2: mid-turn, no offline before half the stall timeout
    without a reply, which here comes after the stall)."""
    v = turning(rig("rot2prog"), 200.0)
    t = v.now
    v.jam()
    v.run_for(6)
    v.set_silent(True)
    v.run_for(10)

    [stall] = v.errors("stalled", since=t)
    assert "no progress for 10 s" in stall.message


def test_a_line_gone_to_garbage_mid_turn_goes_offline_before_a_stall_with_a_long_timeout(
    rig: Rig,
) -> None:
    """silence_timeout_s 20, twice stall_timeout_s: a GS-232B whose every reply is garbled
    from mid-turn on goes offline with words that say so before the turn could be called
    stalled (controller.py rule 2: one timeout at least after the last valid reply came
    after the stall)."""
    v = turning(rig("gs232b", settings={"silence_timeout_s": 20.0}), 350.0, after_s=1)
    t = v.now
    v.to_host = lambda data, now: data.replace(b"=", b"?")  # every reply garbled from now on
    v.run_for(25)

    assert v.errors("stalled", since=t) == []
    assert MotionState.STALLED not in {s.state for s in v.published(since=t)}
    [(off, why)] = [(at, e) for at, e in v.events if at >= t and e.kind == "serial"]
    assert "only garbled replies" in why.message
    assert "a noisy line? A stop sent, in case it still hears" in why.message
    assert off - t < 10.0, off - t


def test_a_jammed_rot2prog_that_answers_is_still_called_stalled(rig: Rig) -> None:
    """Readings that show no progress are a stall as ever, however long silence_timeout_s is
    (controller.py rule 2 cuts the silence short mid-turn only for a line with no reading)."""
    v = turning(rig("rot2prog"), 200.0)
    t = v.now
    v.jam()
    v.run_for(20)

    [stall] = v.errors("stalled", since=t)
    assert "no progress for 10 s" in stall.message
    assert v.errors("serial", since=t) == []
    assert v.status.available


@pytest.mark.parametrize(
    ("model", "settings", "az", "silent_s"),
    [("rot2prog", {}, 40.0, 4.0), ("gs232b", {"stall_timeout_s": 3.0}, 200.0, 1.3)],
)
def test_a_short_silence_mid_turn_is_ridden_out(
    rig: Rig, model: str, settings: dict[str, float], az: float, silent_s: float
) -> None:
    """Replies lost mid-turn for less than the least mid-turn silence (controller.py rule 2:
    half the stall timeout, and the default silence timeout, 3 s, at least): the controller
    stays online and the rotor arrives with no error. A Rot2Prog at its defaults silent 4 s;
    a GS-232B with stall_timeout_s 3 silent 1.3 s, two exchanges at its 1 s reply timeout (an
    attack pass: at half the stall timeout, 1.5 s, it went offline 20 times in 20, and a noisy
    line's RC2800 38 times in 63 turns)."""
    v = rig(model, settings=settings)
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    t = v.now
    v.target(az)
    v.run_until(lambda h: h.state is MotionState.MOVING, 5, "moving")
    v.set_silent(True)
    v.run_for(silent_s)
    v.set_silent(False)
    v.run_until(lambda h: h.state is IDLE, 60, "arrived")

    assert v.errors("serial", since=t) == [] and v.errors("stalled", since=t) == []
    assert {s.available for s in v.published(since=t)} == {True}
    assert abs(v.status.bearing_deg - az) <= 3.0


def test_the_least_mid_turn_silence_is_the_default_silence_timeout() -> None:
    """controller.py rule 2 rides out the default silence timeout mid-turn at least: the two
    numbers are one."""
    assert TURN_SILENCE_LEAST_S == DEFAULT_SILENCE_TIMEOUT_S


def test_a_jammed_gs232b_whose_replies_go_to_garbage_is_stopped_where_the_stall_would_be(
    rig: Rig,
) -> None:
    """A GS-232B at its defaults turning to 350 jams; 4 s later every reply comes garbled: it
    goes offline before the stall the readings were leading to, and gets the stop that stall
    would have written, in case it still hears (an attack pass: offline at the stall check,
    garbage alone not yet enough, and no stop: the motor drove on against the jam)."""
    v = turning(rig("gs232b"), 350.0)
    t = v.now
    v.jam()
    v.run_for(4)
    v.to_host = lambda data, now: data.replace(b"=", b"?")  # every reply garbled from now on
    v.run_for(30)

    [why] = v.errors("serial", since=t)
    assert "only garbled replies" in why.message
    assert "a noisy line? A stop sent, in case it still hears" in why.message
    assert v.sent(since=t).count(b"S\r") >= 1
    assert not v.truth().is_moving


def test_a_stop_owed_to_a_line_gone_to_garbage_is_said_in_one_sentence(rig: Rig) -> None:
    """An operator's STOP mid-turn, then every reply garbled: offline with the words for the
    garbage and for the stop owed, each its own sentence (a last read: "a noisy line?; the
    last stop")."""
    v = turning(rig("gs232b"), 350.0)
    v.stop()
    v.run_for(0.1)
    t = v.now
    v.to_host = lambda data, now: data.replace(b"=", b"?")  # every reply garbled from now on
    v.run_for(15)

    [why] = v.errors("serial", since=t)
    assert "a noisy line? The last stop, no reading showed taking, goes again" in why.message
