"""session/link.py's slews: how long a silent controller's move may take, and how long its
report is waited for."""

from __future__ import annotations

import pytest

from bridge.emulators.spid_models import position_reply
from bridge.protocols.base import PositionReply
from bridge.protocols.rc2800 import MODELS as RC2800
from bridge.protocols.rotorez import MODELS as ROTOREZ
from bridge.protocols.rt21 import MODELS as RT21
from bridge.protocols.satel import MODELS
from bridge.protocols.spid import MODELS as SPID
from bridge.session.link import LATE_EASE, LATE_MAX_S, Link
from bridge.session.slew import SLEW_MARGIN_S, SLEW_TIME_FACTOR, Slew


@pytest.mark.parametrize(
    ("start", "to", "expected_s"),
    [
        ((10.0, 5.0), (100.0, 20.0), 15.0),  # az 90 deg at 6: 15 s; el 15 deg at 2.5: 6 s
        ((10.0, 5.0), (20.0, 80.0), 30.0),  # the elevation decides
        ((350.0, 0.0), (10.0, 0.0), 340 / 6),  # the long way: no wrap past the north stop
        ((None, None), (100.0, 20.0), 360 / 6),  # start unknown: whole spans
    ],
)
def test_travel_time_is_the_slower_axis(
    start: tuple[float | None, float | None], to: tuple[float, float], expected_s: float
) -> None:
    slew = Slew(0.0, *start, *to)
    assert slew.travel_s(6.0, 2.5, 360.0, 90.0) == pytest.approx(expected_s)


def test_a_slews_report_is_owed_until_its_bound_and_each_stop_brings_it_forward() -> None:
    spec = MODELS["satel"]
    link = Link(spec.codec_factory(), spec, 100.0, spec.baud)
    link.send(link.codec.encode_target(100, 20), 100.0)
    # no gap between `g` and `p`: both go at once, so a stop cannot fall between them and
    # cancel the point alone (the slew would be owed for a point never sent)
    assert b"".join(link.output()) == b"gp100 20\r\n"
    link.flush_outbox(200.0)
    assert link.output() == []  # nothing was left waiting for a gap
    link.begin_slew(Slew(100.0, 10.0, 5.0, 100.0, 20.0), 15.0)
    assert 100.0 + SLEW_TIME_FACTOR * 15.0 + SLEW_MARGIN_S == 135.0
    assert not link.reply_overdue(134.9) and link.reply_overdue(135.0)
    assert not link.free() and link.free(for_stop=True)  # only a stop may go into the slew
    for n, t in enumerate((120.0, 122.0), start=1):
        link.want_stop()
        assert link.flush_stop(t)  # a stop may go into a slew
        assert link.slew is not None and link.slew.stops == n
        due_t = t + spec.reply_timeout_s  # the report now comes within one reply time
        assert not link.reply_overdue(due_t - 1e-6) and link.reply_overdue(due_t)
    assert b"".join(link.output()) == b"ss"
    link.give_up_reply(124.0)
    assert link.slew is None and not link.reply_owed and link.silent_for(124.5) == 0.5


# -- rule 7: a poll's reply is read in one go ----------------------------------------------------
def test_a_polls_reply_is_held_until_it_can_be_whole_then_for_what_is_missing() -> None:
    spec = ROTOREZ["rotorez"]  # "AI1;" -> ";123": 4 + 4 bytes at 4800 baud, 10 bits a byte
    byte_s = 10 / 4800
    link = Link(spec.codec_factory(), spec, 0.0, 4800)
    link.poll(10.0, 1.0)
    assert b"".join(link.output()) == b"AI1;"
    assert link.hold_reads_until() == pytest.approx(10.0 + 9 * byte_s)  # + a byte to turn round
    # its end may be met one quiet time (rule 9: three byte times) late, with other lines
    assert link.hold_reads_latest() == pytest.approx(10.0 + 9 * byte_s + 3 * byte_s)
    link.got_bytes(2, 10.03)  # a slow controller: half of the reply so far
    assert link.hold_reads_until() == pytest.approx(10.03 + 2 * byte_s)
    assert link.hold_reads_latest() == pytest.approx(10.03 + 2 * byte_s + 3 * byte_s)
    link.got_bytes(2, 10.04)
    assert link.hold_reads_until() == 0.0  # whole: nothing held any more
    assert link.hold_reads_latest() == 0.0


BYTE_S = 10 / 4800  # a byte at the Rotor-EZ's 4800 baud, 8N1


def exchange(link: Link, t: float, arrivals: list[tuple[float, bytes]]) -> list[float]:
    """One poll at ``t`` (on a grid of 0.5 s) of a Rotor-EZ link whose reply arrives in the
    port as ``arrivals`` (when, bytes), read as worker.py reads it: at each hold's end, and when
    the hold has ended with the reply not whole, as the next bytes arrive. The reading is taken
    after its quiet time. The times of the reads (a read that found nothing included)."""
    link.poll(t, 0.5)
    assert link.output() == [b"AI1;"]
    reads: list[float] = []
    pending = sorted(arrivals)
    while True:
        hold = link.hold_reads_until()
        at = hold if hold > (reads[-1] if reads else t) else pending[0][0]
        data = b"".join(chunk for when, chunk in pending if when <= at)
        pending = [(when, chunk) for when, chunk in pending if when > at]
        reads.append(at)
        link.got_bytes(len(data), at)
        replies = link.codec.feed(data)
        if replies:
            (reply,) = replies
            assert isinstance(reply, PositionReply) and link.hold_reading(reply, at)
            assert link.settled(at + 0.01) is reply
            link.got_reading(at + 0.01)
            return reads


def streamed(start: float, reply: bytes = b";123") -> list[tuple[float, bytes]]:
    """``reply`` as a UART sends it from ``start``: a byte each byte time."""
    return [(start + (i + 1) * BYTE_S, reply[i : i + 1]) for i in range(len(reply))]


def test_a_controller_that_is_always_late_has_each_reply_read_once_from_its_third_on() -> None:
    """Rule 7: a Rotor-EZ that turns round in 3 ms, not the one byte time (2.08 ms) the hold
    allows: its first two replies are read twice (in part at the hold's end, then the rest),
    and from then on the hold waits for it: one read per reply, at most a byte time after it
    is whole (the latency a reading pays for it)."""
    spec = ROTOREZ["rotorez"]
    link = Link(spec.codec_factory(), spec, 0.0, 4800)
    for n in range(20):
        t = 10.0 + 0.5 * n
        sent = t + 4 * BYTE_S + 0.003  # the query on the line, then the turn-round
        arrivals = streamed(sent)
        reads = exchange(link, t, arrivals)
        whole = arrivals[-1][0]
        if n < 2:
            assert len(reads) == 2 and reads[0] < whole <= reads[1]
        else:
            assert reads == [pytest.approx(reads[0])] and whole <= reads[0] <= whole + BYTE_S


def test_a_late_reply_delivered_in_one_chunk_is_waited_for_from_the_fourth_poll_on() -> None:
    """Rule 7: a USB adapter that hands the whole reply over 12 ms after it is on the line
    (its latency timer): the hold ends with nothing there, the port is watched and the reply
    read as it comes. The second such reply in a row raises the hold by a quiet time (three
    byte times), the third by the rest: from the fourth poll on the hold lasts until the
    reply has come."""
    spec = ROTOREZ["rotorez"]
    link = Link(spec.codec_factory(), spec, 0.0, 4800)
    for n, waited in enumerate((0, 0, 3, None, None, None)):
        t = 10.0 + 0.5 * n
        delivered = t + 9 * BYTE_S + 0.012
        reads = exchange(link, t, [(delivered, b";123")])
        if waited is not None:  # nothing at the hold's end, then all of it as it came
            assert reads == [pytest.approx(t + (9 + waited) * BYTE_S), delivered]
        else:
            assert len(reads) == 1 and delivered <= reads[0] <= delivered + BYTE_S


def test_a_reply_late_now_and_then_holds_none_longer_two_in_a_row_a_quiet_time_at_most() -> None:
    """Rule 7: a reply a whole second late (a controller busy, a busy machine) after replies
    in time makes the next hold no longer; two in a row make it a quiet time longer at most;
    a controller on time again has its hold come back down by LATE_EASE of the learned
    lateness per reply. However late the replies, the hold is at most LATE_MAX_S longer."""
    spec = ROTOREZ["rotorez"]
    link = Link(spec.codec_factory(), spec, 0.0, 4800)
    for n in range(199):  # one in ten a second late (the last in time)
        t = 10.0 + 2.0 * n
        late = n % 10 == 9
        exchange(link, t, [(t + 1.0, b";123")] if late else streamed(t + 4 * BYTE_S))
        assert link.late_s == 0.0
    exchange(link, 500.0, [(501.0, b";123")])
    exchange(link, 510.0, [(511.0, b";123")])
    assert link.late_s == pytest.approx(3 * BYTE_S)
    holds = []
    for n in range(1, 601):
        t = 512.0 + 0.5 * n
        exchange(link, t, streamed(t + 4 * BYTE_S))  # on time: whole at 8 byte times
        holds.append(link.late_s)
    assert holds[0] == pytest.approx(3 * BYTE_S * (1 - LATE_EASE))
    assert holds[-1] == pytest.approx(3 * BYTE_S * (1 - LATE_EASE) ** 600)
    assert holds[-1] < 3 * BYTE_S / 9
    for n in range(40):
        t = 900.0 + 0.5 * n
        exchange(link, t, [(t + 0.4, b";123")])
    assert link.late_s == LATE_MAX_S


def test_a_poll_of_two_frames_learns_no_lateness() -> None:
    """Rule 7: an RC2800 asks its two axes in two frames, the second after the axis gap; its
    hold counts both replies from the first, so the elevation's always comes "late". That is
    no lateness of the box: its holds stay as long as the line rate says."""
    spec = RC2800["rc2800"]
    link = Link(spec.codec_factory(), spec, 0.0, spec.baud)
    byte_s = 10 / spec.baud
    for n in range(10):
        t = 10.0 + 2.0 * n
        link.poll(t, 2.0)
        assert link.output() == [b"A\r"]
        hold = link.hold_reads_until()
        assert hold == pytest.approx(t + (2 + spec.reply_bytes + 1) * byte_s)
        az = b"A P= 98.1 S=9 MV\r"
        link.got_bytes(len(az), hold)
        assert link.codec.feed(az) == []  # the elevation's is owed
        link.flush_outbox(t + 1.0)
        assert link.output() == [b"E\r"]
        el = b"E=43.7 S=9 M\r"
        link.got_bytes(len(el), t + 1.1)
        (reading,) = link.codec.feed(el)
        assert isinstance(reading, PositionReply) and link.hold_reading(reading, t + 1.1)
        assert link.settled(t + 1.5) is reading
        link.got_reading(t + 1.5)
        assert link.late_s == 0.0


@pytest.mark.parametrize("model", ["rot2prog", "md01"])
def test_a_stop_due_ends_the_hold_so_it_goes_as_soon_as_the_reply_is_whole(model: str) -> None:
    """Rules 3 and 7: a SPID takes no frame while it replies, so a stop waits for the reply;
    but not for the hold's end (its lateness learned included): the port is read at once."""
    spec = SPID[model]
    link = Link(spec.codec_factory(), spec, 0.0, spec.baud)
    link.late_s = 0.02
    link.poll(10.0, 1.0)
    assert len(link.output()) == 1
    assert link.hold_reads_until() > 10.0 and link.hold_reads_latest() > 10.0
    link.want_stop()
    assert not link.flush_stop(10.001)  # the reply is owed
    assert link.hold_reads_until() == 0.0 and link.hold_reads_latest() == 0.0
    reply = position_reply(spec, 123.0, 45.0, 2)
    t = 10.0 + spec.exchange_time_s()  # whole: read as it came
    link.got_bytes(len(reply), t)
    (reading,) = link.codec.feed(reply)
    assert isinstance(reading, PositionReply) and link.hold_reading(reading, t)
    assert link.flush_stop(t)


def test_a_read_of_nothing_that_a_stop_brought_forward_teaches_no_lateness() -> None:
    """Rule 7: a stop due on a Rot2Prog ends the hold at once; the read then finds nothing
    (the reply is on its way), which says nothing about how late the reply is. Two replies
    in a row read that way, each whole a little after the line rate's time, teach nothing."""
    spec = SPID["rot2prog"]
    link = Link(spec.codec_factory(), spec, 0.0, spec.baud)
    link.late_s = 0.001
    for n in range(3):
        t = 10.0 + 5.0 * n
        link.poll(t, 5.0)
        assert len(link.output()) == 1
        base = link.hold_reads_until() - link.late_s
        link.want_stop()
        assert link.hold_reads_until() == 0.0
        link.got_bytes(0, t + 0.01)  # read at once: nothing yet
        whole = base + 0.003
        reply = position_reply(spec, 123.0, 45.0, 2)
        link.got_bytes(len(reply), whole)  # read as it came (the port watched)
        (reading,) = link.codec.feed(reply)
        assert isinstance(reading, PositionReply) and link.hold_reading(reading, whole)
        assert link.flush_stop(whole)
        link.output()
        assert link.settled(whole) is reading
        link.got_reading(whole)
        (answer,) = link.codec.feed(reply)  # the stop's own reply
        assert isinstance(answer, PositionReply) and link.hold_reading(answer, whole + 0.5)
        assert link.settled(whole + 1.0) is answer
        link.got_reading(whole + 1.0)
    assert link.late_s == 0.001  # neither raised nor eased


def test_two_late_replies_in_a_row_raise_the_hold_to_the_less_late_of_the_two() -> None:
    """Rule 7: replies whole 4 ms and then 2 ms after the hold's end (in one chunk each, as
    an adapter hands them over): the hold is raised to the second's lateness and a byte time,
    not the first's."""
    spec = ROTOREZ["rotorez"]
    link = Link(spec.codec_factory(), spec, 0.0, 4800)
    for n, late in enumerate((0.004, 0.002)):
        t = 10.0 + 0.5 * n
        exchange(link, t, [(t + 9 * BYTE_S + late, b";123")])
    assert link.late_s == pytest.approx(0.002 + BYTE_S)


def test_a_short_reply_whole_at_the_holds_end_teaches_no_lateness() -> None:
    """Rule 7: an RT-21 sends a bearing under 100 degrees without a leading zero (``45.0;``,
    a byte short of the ``123.4;`` its hold counts on): whole at the hold's end, it makes the
    next hold no longer."""
    spec = RT21["rt21"]
    link = Link(spec.codec_factory(), spec, 0.0, spec.baud)
    for n in range(3):
        link.poll(10.0 + n, 1.0)
        assert link.output()
        at = link.hold_reads_until()
        link.got_bytes(5, at)
        (reply,) = link.codec.feed(b"45.0;")
        assert isinstance(reply, PositionReply) and link.hold_reading(reply, at)
        assert link.settled(at + 1.0) is reply
        link.got_reading(at + 1.0)
        assert link.late_s == 0.0


# -- rule 8: polls on a grid ----------------------------------------------------------------------
def test_polls_keep_to_a_grid_of_their_interval_so_rotators_poll_together() -> None:
    spec = ROTOREZ["rotorez"]
    times = {}
    for name, start in (("a", 3.1234), ("b", 3.2071)):  # links that came up at odd moments
        link = Link(spec.codec_factory(), spec, start, 4800)
        t, polls = start, []
        while t < 5.0:
            link.poll(t, 0.2)
            if link.output():
                polls.append(t)
                link.codec.feed(b";123")  # the reply came
                link.got_reading(t + 0.017)
            t += 0.0001
        times[name] = polls
    a, b = times["a"], times["b"]
    assert a[0] == 3.1234 and b[0] == 3.2071  # the first at once ...
    assert a[1] == pytest.approx(3.4, abs=2e-4) and b[1] == pytest.approx(3.4, abs=2e-4)
    assert a[1:] == pytest.approx(b[1:], abs=2e-4)  # ... then together on the grid
    assert [y - x for x, y in zip(a[1:], a[2:], strict=False)] == pytest.approx([0.2] * 7, abs=2e-4)


# -- rule 9: the quiet time after a reading holds no stop back -----------------------------------
@pytest.mark.parametrize("model", ["rot2prog", "rot1prog", "md01"])
def test_a_stop_goes_out_at_once_while_a_whole_reply_is_held_for_the_quiet_time(model: str) -> None:
    """A half-duplex SPID takes no frame while a reply is owed, and a stop does not interrupt
    one (no ``stop_interrupts``); but a reply that has come whole is no reply owed. The stop
    goes out the instant it is wanted, the held reading is taken as it stands, and the stop's
    own reply is a reading of its own exchange, not a second reply spoiling the held one."""
    spec = SPID[model]
    link = Link(spec.codec_factory(), spec, 0.0, spec.baud)
    link.poll(10.0, 1.0)
    assert len(link.output()) == 1  # the status query
    reply = position_reply(spec, 123.0, 45.0, 2)
    t = 10.0 + spec.exchange_time_s()  # the whole reply is in
    link.got_bytes(len(reply), t)
    (reading,) = link.codec.feed(reply)
    assert isinstance(reading, PositionReply) and link.hold_reading(reading, t)
    assert link.settled(t) is None  # held for the quiet time
    link.want_stop()
    assert link.flush_stop(t)  # at once, not after the quiet time
    assert link.output() == [b"\x57" + bytes(10) + b"\x0f\x20"]
    assert link.settled(t) is reading  # the reading the stop cut short, as it stands
    assert link.reply_owed and not link.reply_overdue(t + spec.reply_timeout_s - 1e-6)
    later = t + spec.exchange_time_s()
    link.got_bytes(len(reply), later)
    (answer,) = link.codec.feed(reply)  # the stop's reply
    assert isinstance(answer, PositionReply) and link.hold_reading(answer, later)
    assert link.settled(later + 1.0) is answer


def test_a_stop_drops_a_held_reading_that_bytes_after_it_spoil() -> None:
    """Rule 9: a glitch ``;359`` held for the quiet time while the real ``;180`` is arriving
    (its first bytes are in, the codec waits for the rest). A STOP pressed then goes out at
    once, but the held reading is not taken as it stands: it is dropped, never published nor
    judged as a move, and the controller is asked again."""
    spec = ROTOREZ["rotorez"]
    link = Link(spec.codec_factory(), spec, 0.0, spec.baud)
    link.poll(10.0, 1.0)
    assert link.output() == [b"AI1;"]
    t = 10.0 + spec.exchange_time_s()
    link.got_bytes(4, t)
    (reading,) = link.codec.feed(b";359")
    assert isinstance(reading, PositionReply) and link.hold_reading(reading, t)
    later = t + 2 * 10 / spec.baud  # two byte times on
    link.got_bytes(2, later)
    assert link.codec.feed(b";1") == []  # the real reply is coming
    link.want_stop()
    assert link.flush_stop(later)
    assert link.output() == [spec.codec_factory().encode_stop()]  # at once
    assert link.settled(later + 1.0) is None  # the glitch is no reading
    link.poll(later, 1.0)
    assert link.output() == [b"AI1;"]  # asked again


# -- rule 10: a controller that needs time between its axes -------------------------------------
def test_an_rc2800s_axes_get_their_200_ms_and_a_stop_waits_for_nothing() -> None:
    """A target's and a poll's frames go 200 ms apart, the next frame no sooner after the last;
    a stop's first frame goes at once (and cancels what waits), its second 200 ms later. (The
    box answers each axis's frame, both turning: the codec's stop begins with the azimuth,
    rc2800.py rule 9.)"""
    spec = RC2800["rc2800"]
    link = Link(spec.codec_factory(), spec, 0.0, spec.baud)

    def wire(start: float, until: float, poll: bool = True) -> list[tuple[float, bytes]]:
        out: list[tuple[float, bytes]] = []
        t = start
        while t <= until + 1e-9:
            link.flush_outbox(t)
            if poll:
                link.poll(t, 0.1)
            out += [(round(t, 2), frame) for frame in link.output()]
            t += 0.01
        return out

    link.send(link.codec.encode_target(100, 20), 0.0)
    link.poll_now(0.0)
    assert wire(0.0, 0.1) == [(0.0, b"A100.0\r")]
    link.codec.feed(b"A P= 0.5 S=9 MV\r")  # its answer
    assert wire(0.11, 0.3) == [(0.2, b"E20.0\r")]
    link.codec.feed(b"E P= 0.3 S=9 MV\r")
    assert wire(0.31, 0.5) == [(0.4, b"A\r")]
    assert link.wakeups()[0] == pytest.approx(0.6)  # the poll's E
    link.want_stop()
    assert link.flush_stop(0.5)  # at once, 100 ms after the last frame: a stop never waits
    assert link.output() == [b"A\rS\r"]
    link.send(link.codec.encode_target(200, 30), 0.55)
    assert link.output() == []  # after the stop's elevation frame, then 200 ms apart
    assert wire(0.55, 1.15, poll=False) == [
        (0.7, b"E\rS\r"),
        (0.7, b"E30.0\r"),  # the axis last addressed first: no gap needed
        (0.9, b"A200.0\r"),
    ]


def test_a_controller_without_an_axis_gap_sends_as_before() -> None:
    spec = RC2800["rc2800-az"]
    link = Link(spec.codec_factory(), spec, 0.0, spec.baud)
    link.send(link.codec.encode_target(100), 0.0)
    link.poll(0.0, 0.1)
    assert link.output() == [b"A100.0\r", b"A\r"]
    link.want_stop()
    assert link.flush_stop(0.0) and link.output() == [b"A\rS\r"]


def test_an_rc2800_target_takes_the_place_of_a_polls_waiting_frame_and_the_axis_it_asked() -> None:
    """A target while a poll's elevation frame waits: the poll's frame is dropped (the target's
    answers answer it) and the target's azimuth goes at once (the axis just asked), its
    elevation 200 ms later; after a poll's elevation frame it would go elevation first."""
    spec = RC2800["rc2800"]
    link = Link(spec.codec_factory(), spec, 0.0, spec.baud)
    link.poll(0.0, 1.0)
    assert link.output() == [b"A\r"]
    link.send(link.codec.encode_target(100, 20), 0.05)
    assert link.output() == [b"A100.0\r"]
    assert link.wakeups()[0] == pytest.approx(0.25)
    link.flush_outbox(0.25)
    assert link.output() == [b"E20.0\r"]  # and no E\r of the poll's
    link.send(link.codec.encode_target(110, 25), 0.3)
    assert link.output() == [b"E25.0\r"]
    link.flush_outbox(0.5)
    assert link.output() == [b"A110.0\r"]
