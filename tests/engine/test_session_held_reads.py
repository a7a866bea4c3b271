"""link.py rules 7 and 9 in virtual time, the port read as the real worker reads it (virtual.py
rule 6: a poll's reply left in the port until the hold ends): a reply found whole by that read,
with nothing after it, is taken and published in the step of that read, no later than when the
read at the old end of the hold and the quiet time after it published it; a second reply or
noise begun by then still spoils it; a reply that came in part, or later, keeps its quiet time.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from bridge.emulators.base import Responder
from bridge.session.link import SETTLE_BYTES, SETTLE_MIN_S
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING


def served(v: VirtualRotator) -> list[float]:
    """The instants the session is served at from now on (a read, a tick, a command)."""
    times: list[float] = []
    session = v.session
    for name in ("bytes_received", "tick", "commands"):
        call = getattr(session, name)

        def counted(*args: object, call: Callable[..., object] = call) -> object:
            times.append(float(args[-1]))  # type: ignore[arg-type]
            return call(*args)

        setattr(session, name, counted)
    return times


def byte_s(v: VirtualRotator) -> float:
    return 10 / v.cfg.baud


def quiet_s(v: VirtualRotator) -> float:
    return max(SETTLE_MIN_S, SETTLE_BYTES * byte_s(v))


def query(v: VirtualRotator) -> bytes:
    asked = v.cfg.spec.codec_factory().encode_query()
    assert asked
    return asked[0] if isinstance(asked, list) else asked


def whole_by(v: VirtualRotator, poll_t: float) -> float:
    """When a poll's reply can first be whole: the query, the reply, a byte to turn round
    (where the read was before: rule 7's hold without the quiet time)."""
    return poll_t + (len(query(v)) + v.cfg.spec.reply_bytes + 1) * byte_s(v)


def bearing_changes(v: VirtualRotator, since: float) -> list[float]:
    """The instants a new bearing was published (only a reading changes it)."""
    changes, last = [], None
    for t, status in v.statuses:
        if t >= since and status.bearing_deg != last and last is not None:
            changes.append(t)
        last = status.bearing_deg
    return changes


def last_poll_before(v: VirtualRotator, t: float) -> float:
    return max(w.t for w in v.writes if w.data == query(v) and w.t <= t)


def test_a_turning_rotor_ez_is_served_twice_per_poll_and_each_reading_published_as_it_is_read(
    rig: Rig,
) -> None:
    """Turned from its front panel, polled every 0.2 s at 4800 baud: the session is served at
    the poll and at the read of its reply, once the reply and the quiet time after it can be
    over (12 byte times), and publishes the reading there; before, a read at 9 byte times held
    it and a third wake-up after the quiet time took it, at the same instant."""
    v = rig("rotorez", emulator={"speed_deg_s": 4.0}, reads_held=True)
    v.run_until_state(IDLE, 30)
    v.manual_rotate(350.0)
    v.run_until_state(MOVING, 10)
    v.run_for(1)
    t0 = v.now
    times = served(v)
    v.run_for(10)
    polls = [w.t for w in v.writes if w.data == b"AI1;" and w.t >= t0]
    assert len(polls) >= 45
    assert len(set(times)) <= 2 * len(polls) + 1  # (a poll written just before the end)
    reads = {t for t, _data in v.received if t >= t0}
    changes = bearing_changes(v, t0)
    assert len(changes) >= len(polls) // 2  # (whole degrees: some readings move it none)
    for t in changes:
        poll_t = last_poll_before(v, t)
        assert t in reads  # in the step of the read
        assert t == pytest.approx(poll_t + 12 * byte_s(v))
        assert t <= whole_by(v, poll_t) + quiet_s(v) + 1e-9  # no later than before
    assert v.status.bearing_deg == pytest.approx(v.truth().az_deg, abs=2)


@pytest.mark.parametrize(
    "model", ["rot2prog", "md01", "gs232b", "easycomm3", "rt21", "prosistel", "rc2800-az"]
)
def test_every_family_publishes_a_reply_read_whole_in_the_step_of_its_read(
    rig: Rig, model: str
) -> None:
    """Whatever the codec (fixed frames, lines with CR LF, variable lengths), a reply found
    whole with nothing after it is taken where it is read: every new bearing of a turn is
    published at the instant its reply was read, no later than the old read and quiet time."""
    v = rig(model, reads_held=True)
    v.run_until_state(IDLE, 30)
    spec = v.cfg.spec
    t0 = v.now
    v.target(spec.az_min_deg + 0.6 * (spec.az_max_deg - spec.az_min_deg))
    v.run_until(lambda h: h.state is MOVING, 10, "moving")
    v.run_for(4)
    reads = {t for t, _data in v.received if t >= t0}
    changes = bearing_changes(v, t0)
    assert len(changes) >= 3
    for t in changes:
        assert t in reads
        assert t <= whole_by(v, last_poll_before(v, t)) + quiet_s(v) + 1e-9


class Late:
    """The device behind an adapter that hands on what it received in one chunk ``late_s``
    after the first byte of it (a USB adapter's latency timer), or with ``extra`` bytes of
    line noise of its own at set instants."""

    def __init__(self, device: Responder, late_s: float = 0.0) -> None:
        self.device = device
        self.late_s = late_s
        self.extra: list[tuple[float, bytes]] = []
        self._held = b""
        self._due = 0.0

    def __getattr__(self, name: str) -> object:
        return getattr(self.device, name)

    def due_output(self, now: float) -> bytes:
        out = self.device.due_output(now)
        if self.late_s and out:
            if not self._held:
                self._due = now + self.late_s
            self._held += out
            out = b""
        if self._held and now >= self._due:
            out, self._held = self._held, b""
        while self.extra and self.extra[0][0] <= now:
            out += self.extra.pop(0)[1]
        return out

    def next_wakeup(self, now: float) -> float | None:
        times = [t for t in (self.device.next_wakeup(now),) if t is not None]
        times += [self._due] if self._held else []
        times += [self.extra[0][0]] if self.extra else []
        return min(times) if times else None


def polled(v: VirtualRotator, timeout_s: float = 5) -> float:
    """Run until the next poll is written; its instant."""
    count = len(v.writes)
    v.run_until(lambda h: any(w.data == query(h) for w in h.writes[count:]), timeout_s, "poll")
    return next(w.t for w in v.writes[count:] if w.data == query(v))


def test_a_reply_that_came_in_part_is_read_again_for_the_rest_and_keeps_its_quiet_time(
    rig: Rig,
) -> None:
    """A Rotor-EZ slow to turn round (10 ms): three bytes of ";180" are in when the hold ends
    (12 byte times after the poll), the fourth a byte time later is read then (rule 7), and the
    reading is taken only after the quiet time that follows that read (rule 9), as before."""
    v = rig(
        "rotorez",
        emulator={"start_az_deg": 170.0, "processing_delay_s": 0.010, "speed_deg_s": 4.0},
        reads_held=True,
    )
    v.run_until_state(IDLE, 30)
    v.manual_rotate(190.0)
    v.run_until_state(MOVING, 10)
    t0 = v.now
    v.run_for(3)
    b = byte_s(v)
    changes = bearing_changes(v, t0)
    assert len(changes) >= 5
    for t in changes:
        poll_t = last_poll_before(v, t)
        reads = [(rt - poll_t, data) for rt, data in v.received if poll_t < rt <= t]
        assert [len(data) for _, data in reads] == [3, 1]
        assert reads[0][0] == pytest.approx(12 * b)
        assert reads[1][0] == pytest.approx(13 * b)
        assert t - poll_t == pytest.approx(13 * b + quiet_s(v))


def test_a_reply_an_adapter_hands_on_late_in_one_chunk_keeps_its_quiet_time(rig: Rig) -> None:
    """Nothing is in the port when the hold ends (an adapter that hands bytes on 16 ms late):
    the port is watched, and the reply that then comes whole in one chunk is held for the
    quiet time after it (rule 9: the line was not seen quiet after it), not taken at once."""
    v = rig("rotorez", emulator={"start_az_deg": 170.0, "speed_deg_s": 4.0}, reads_held=True)
    v.device = Late(v.device, late_s=0.016)
    v.run_until_state(IDLE, 30)
    v.manual_rotate(190.0)
    v.run_until_state(MOVING, 10)
    t0 = v.now
    v.run_for(3)
    changes = bearing_changes(v, t0)
    assert len(changes) >= 5
    for t in changes:
        poll_t = last_poll_before(v, t)
        reads = [rt for rt, _data in v.received if poll_t < rt <= t]
        assert len(reads) == 1 and reads[0] > poll_t + 12 * byte_s(v)
        assert t == pytest.approx(reads[0] + quiet_s(v))


def test_a_glitch_before_a_real_reply_still_coming_when_the_hold_ends_is_no_reading(
    rig: Rig,
) -> None:
    """A glitch ``;359`` just before the real ``;180`` of a controller slow to turn round:
    the read at the hold's end finds the glitch whole and the real reply begun. The glitch is
    not taken there: the bytes of the frame begun hold it, the real reply spoils it, neither
    is published, and the controller is asked again at once."""
    v = rig(
        "rotorez",
        emulator={"start_az_deg": 180.0, "processing_delay_s": 0.010},
        reads_held=True,
    )
    v.run_until_state(IDLE, 30)
    v.run_for(1)
    glitched = v.glitch_once(b";", b";359")
    t = v.now
    v.run_for(3)
    assert glitched
    assert {s.bearing_deg for s in v.published(since=t)} <= {180.0}
    asked = [w.t for w in v.writes if w.data == b"AI1;" and w.t > glitched[0]]
    assert asked[0] - glitched[0] < 0.1  # asked again at once, not at the next idle poll


def test_a_glitch_begun_after_the_real_reply_when_the_hold_ends_still_spoils_it(
    rig: Rig,
) -> None:
    """Noise that forms a second ``;359`` starting after the real ``;180`` ended and still
    arriving when the hold ends: the real reading is not taken at the read (a frame has begun
    after it), the second reply spoils the exchange, and the controller is asked again at once
    (the noise is reported, no bearing 359 is published)."""
    v = rig("rotorez", emulator={"start_az_deg": 180.0}, reads_held=True)
    late = Late(v.device)
    v.device = late
    v.run_until_state(IDLE, 30)
    v.run_for(1)
    poll_t = polled(v)
    b = byte_s(v)
    end = whole_by(v, poll_t)
    late.extra = [(end + 0.5 * b, b";"), (end + 1.5 * b, b"3"), (end + 3.5 * b, b"59")]
    v.run_for(0.15)
    assert {t for t, _ in v.received if t > poll_t} >= {end + 3 * b, end + 3.5 * b}
    asked = [w.t for w in v.writes if w.data == b"AI1;" and w.t > poll_t]
    assert asked[0] - poll_t < 0.05  # asked again at once, not at the next idle poll
    assert {s.bearing_deg for s in v.published(since=poll_t)} <= {180.0}


def test_a_stop_waiting_for_a_half_duplex_reply_in_the_port_reads_it_without_the_quiet_time(
    rig: Rig,
) -> None:
    """A Rot2Prog at 600 baud (a quiet time of 50 ms): a STOP pressed while a poll's reply is
    on its way waits for it (half duplex, link.py rule 3), and the port is read as soon as the
    reply can be whole, not a quiet time later: the stop goes out with that read."""
    v = rig("rot2prog", emulator={"start_az_deg": 100}, reads_held=True)
    v.run_until_state(IDLE, 30)
    v.target(150)
    v.run_until(lambda h: h.state is MOVING and h.truth().is_moving, 30, "moving")
    poll_t = polled(v)
    v.run_until(lambda h: h.now > poll_t + 0.1, 1, "the reply on its way")
    t = v.now
    v.stop()
    assert [w for w in v.writes if w.t >= t] == []  # half duplex: the reply first
    v.run_until(lambda h: h.writes[-1].t > t, 1, "the stop")
    assert v.writes[-1].data[11] == 0x0F
    assert v.writes[-1].t == pytest.approx(whole_by(v, poll_t))
    assert v.received[-1][0] == v.writes[-1].t  # with the read of the reply
    v.run_until(lambda h: h.state is IDLE and not h.truth().is_moving, 30, "stopped")
    assert v.truth().az_deg < 149


@pytest.mark.parametrize("reads_held", [False, True])
def test_a_reply_that_ends_just_before_its_deadline_is_taken_and_nothing_spins(
    rig: Rig, reads_held: bool
) -> None:
    """A Rotor-EZ that answers 230 ms after a poll, its reply whole a few ms before the 250 ms
    reply deadline: the reading's quiet time runs past the deadline, the reply is not overdue
    meanwhile (link.py rule 9), and the session does not ask to be woken at that deadline
    again and again until the quiet time is over (before: the loop spun on it, virtual.py
    rule 4). Every reading is taken."""
    v = rig(
        "rotorez",
        emulator={"start_az_deg": 42.0, "processing_delay_s": 0.230},
        reads_held=reads_held,
    )
    v.run_until_state(IDLE, 30)
    t = v.now
    v.run_for(10)
    assert v.spins == [] and v.errors(since=t) == []
    assert v.status.available
    assert v.status.bearing_deg == pytest.approx(v.truth().az_deg, abs=1)


@pytest.mark.parametrize("model", ["rot2prog", "rt21"])
def test_a_line_too_slow_for_the_quiet_time_before_the_reply_deadline_is_read_as_before(
    rig: Rig, model: str
) -> None:
    """At 110 baud the reply and its quiet time are not over by the model's reply deadline
    (link.py rule 7): the reply is read as soon as it can be whole, as before, and held for
    its quiet time, not given up at the deadline with the bytes still in the port."""
    v = rig(model, settings={"baud": 110}, emulator={"baud": 110}, reads_held=True)
    v.run_for(30)
    assert v.state is IDLE and v.status.available
    assert v.errors() == []
