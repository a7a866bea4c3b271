"""session.py rule 16 in virtual time: the bytes that complete a reading held for its quiet time
(link.py rule 9) run no session step of their own, and nothing that such a step did for a user
comes later for it: a stop already waiting goes out the instant the reply is whole.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from bridge.emulators.spid_models import K_STATUS
from bridge.session.link import SETTLE_BYTES, SETTLE_MIN_S
from bridge.session.session import Action
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING


def count_steps(v: VirtualRotator) -> list[float]:
    """The times of every session step from now on."""
    steps: list[float] = []
    step = v.session._step

    def counted(now: float) -> list[Action]:
        steps.append(now)
        return step(now)

    v.session._step = counted  # type: ignore[method-assign]
    return steps


def test_a_turning_rotor_ez_costs_two_steps_per_reading_and_each_is_published_after_its_quiet_time(
    rig: Rig,
) -> None:
    """Turned from its front panel, polled every 0.2 s, its replies byte by byte at 4800 baud:
    one step writes the poll, one takes the reading once the line has stayed quiet after it;
    the byte that completes the reply runs none. Every reading is still published, at the end
    of its quiet time (its last byte plus SETTLE_BYTES byte times), as before."""
    v = rig("rotorez", emulator={"speed_deg_s": 4.0})
    v.run_until_state(IDLE, 30)
    v.manual_rotate(350.0)
    v.run_until_state(MOVING, 10)
    v.run_for(1)
    t0 = v.now
    steps = count_steps(v)
    v.run_for(10)
    polls = [w.t for w in v.writes if w.data == b"AI1;" and w.t >= t0]
    assert len(polls) >= 45
    assert len(steps) <= 2 * len(polls) + 1  # (a poll written just before the end, unread)
    settle_s = max(SETTLE_MIN_S, SETTLE_BYTES * 10 / v.cfg.baud)
    published = [t for t, s in v.statuses if t >= t0]
    ends = [t for t, _data in v.received]
    assert len(published) >= len(polls) // 2  # (whole degrees: some readings move it none)
    for t in published:  # each at a reply's last byte plus the quiet time
        assert any(t == pytest.approx(end + settle_s) for end in ends), t
    assert v.status.bearing_deg == pytest.approx(v.truth().az_deg, abs=2)


def test_a_turning_gs232b_takes_each_reading_in_one_step_at_the_end_of_its_cr_lf_quiet_time(
    rig: Rig,
) -> None:
    """A GS-232B ends its replies with CR LF: the CR completes the reading, the LF a byte later
    holds it a little longer (link.py rule 9) and completes nothing (gs232.py rule 1). One
    whole step per reading, at the end of the quiet time after the LF: no step for the LF, none
    at the quiet time's old end, none to wait out the LF as junk (before: three per reading).
    Every reading is published then."""
    v = rig("gs232b")
    v.run_until_state(IDLE, 30)
    v.target(300.0)
    v.run_until_state(MOVING, 10)
    v.run_for(1)
    t0 = v.now
    steps = count_steps(v)
    v.run_for(10)
    query = b"C2\r"
    polls = [w.t for w in v.writes if w.data == query and w.t >= t0]
    assert len(polls) >= 45
    assert len(steps) <= len(polls) + 1  # (a poll written just before the end, unread)
    settle_s = max(SETTLE_MIN_S, SETTLE_BYTES * 10 / v.cfg.baud)
    lfs = [t for t, data in v.received if data.endswith(b"\n")]
    published = [t for t, s in v.statuses if t >= t0]
    assert len(published) >= len(polls) - 1
    for t in published:  # each at a reply's LF plus the quiet time
        assert any(t == pytest.approx(lf + settle_s) for lf in lfs), t
    assert v.status.bearing_deg == pytest.approx(v.truth().az_deg, abs=2)


def test_a_stop_waiting_for_a_half_duplex_reply_goes_out_the_instant_the_reply_is_whole(
    rig: Rig,
) -> None:
    """A Rot2Prog at 600 baud, half duplex: a STOP pressed while a poll's reply is coming waits
    for the reply (link.py rule 3), and goes out with the byte that completes it, not after the
    quiet time that follows (the step for that byte is run for the stop)."""
    v = rig("rot2prog", emulator={"start_az_deg": 100})
    v.run_until_state(IDLE, 30)
    v.target(150)
    v.run_until(lambda h: h.state is MOVING and h.truth().is_moving, 30, "moving")
    reply_bytes = v.cfg.spec.reply_bytes

    def got_since_poll(h: VirtualRotator) -> int:
        last = h.writes[-1]
        if last.data[11] != K_STATUS:
            return -1
        return sum(len(data) for t, data in h.received if t > last.t)

    v.run_until(lambda h: got_since_poll(h) == 2, 10, "a poll's reply half in")
    t = v.now
    v.stop()
    assert [w for w in v.writes if w.t >= t] == []  # half duplex: the reply first
    v.run_until(lambda h: got_since_poll(h) >= reply_bytes or h.writes[-1].t > t, 10, "reply")
    stop_t = v.writes[-1].t
    assert v.writes[-1].data[11] == 0x0F
    assert stop_t == v.received[-1][0]  # with the reply's last byte
    v.run_until(lambda h: h.state is IDLE and not h.truth().is_moving, 30, "stopped")
    assert v.truth().az_deg < 149
