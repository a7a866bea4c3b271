"""session.py rule 16 in virtual time: the bytes that complete a reading held for its quiet time
(link.py rule 9) run no session step of their own, and nothing that such a step did for a user
comes later for it: a stop already waiting goes out the instant the reply is whole.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import pytest

from bridge.app import worker_config
from bridge.core.model import MotionState
from bridge.emulators.spid_models import K_STATUS
from bridge.feature import session_parts
from bridge.session.link import SETTLE_BYTES, SETTLE_MIN_S
from bridge.session.parts import Part, Scene, Wake
from bridge.session.session import Action, RotatorSession
from bridge.settings import RotatorSettings
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


def turning(
    v: VirtualRotator, turn: Callable[[], None], query: bytes
) -> tuple[float, list[float], list[float]]:
    """The rotor turned by ``turn`` from rest and polled at the moving rate for 10 s: when that
    began, the times of every session step and of every poll written since."""
    v.run_until_state(IDLE, 30)
    turn()
    v.run_until_state(MOVING, 10)
    v.run_for(1)
    t0 = v.now
    steps = count_steps(v)
    v.run_for(10)
    polls = [w.t for w in v.writes if w.data == query and w.t >= t0]
    assert len(polls) >= 45
    return t0, steps, polls


def test_a_turning_rotor_ez_costs_two_steps_per_reading_and_each_is_published_after_its_quiet_time(
    rig: Rig,
) -> None:
    """Turned from its front panel, polled every 0.2 s, its replies byte by byte at 4800 baud:
    one step writes the poll, one takes the reading once the line has stayed quiet after it;
    the byte that completes the reply runs none. Every reading is still published, at the end
    of its quiet time (its last byte plus SETTLE_BYTES byte times), as before."""
    v = rig("rotorez", emulator={"speed_deg_s": 4.0})
    t0, steps, polls = turning(v, lambda: v.manual_rotate(350.0), b"AI1;")
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
    t0, steps, polls = turning(v, lambda: v.target(300.0), b"C2\r")
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


class Alarm:
    """A deciding part's own state: a time it wants a step at, and when it had one."""

    def __init__(self, s: RotatorSession) -> None:
        self.t: float | None = None
        self.fired: list[float] = []


def _ring(s: RotatorSession, scene: Scene) -> None:
    alarm: Alarm = s.own["alarm"]
    if alarm.t is not None and scene.now >= alarm.t:
        alarm.fired.append(scene.now)
        alarm.t = None


ALARM = Part[RotatorSession](
    "alarm",
    Wake.STEP,
    True,
    lambda s: True,
    _ring,
    lambda s, now: None,
    wakeup=lambda s, now: s.own["alarm"].t,
    state=Alarm,
)


def test_a_deadline_inside_a_quiet_time_held_longer_is_still_met(rig: Rig) -> None:
    """Rule 16: bytes that complete nothing hold a reading longer, and the wake-up moves with
    its quiet time, but never past the step's own: a part's deadline that falls inside the
    longer quiet time still gets its step then (hand-fed replies at chosen times, a GS-232B's
    reply and its LF)."""
    settings = RotatorSettings(id="v", model="gs232b", port="/dev/ttyVIRTUAL")
    cfg = replace(worker_config(settings), parts=(*session_parts(), ALARM))
    v = rig("gs232b", cfg=cfg)
    v.run_until_state(IDLE, 30)
    v.run_for(2.0)
    v.set_silent(True)  # the replies are hand-fed below
    n = len(v.writes)
    v.run_until(lambda h: any(w.data == b"C2\r" for w in h.writes[n:]), 10, "a poll")
    s, polled = v.session, v.now
    due = polled + 0.050
    s.own["alarm"].t = due
    assert s.tick(polled) == []  # a whole step (a deciding part is on): its wake-up is then
    assert s.next_wakeup() == due
    assert s.bytes_received(b"AZ=100  EL=000\r", due - 0.003) == []  # held (rule 16)
    assert s.bytes_received(b"\n", due - 0.002) == []  # completes nothing, holds it longer
    assert s.next_wakeup() <= due  # not the longer quiet time's end
    s.tick(due)
    assert s.own["alarm"].fired == [due]
