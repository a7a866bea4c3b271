"""What a soak failure turned out to be, proven in virtual time: a Rot2Prog's last reading lags.

The soak (tests/soak/runner.py, seed 784776513) failed at its very end with "retained state
wrong at the end: spid bearing 26.0 vs 20.0": the Rot2Prog (600 baud, 10 deg/s in the soak) had
been sent 20 from 345, the retained bearing said 26 while the emulator stood at 20, and the bridge
log had no "arrived at 20". The timing explains all of it: the final targets went out when the
soak's first end wait ran out (16:33:51 in that log), 345 -> 20 takes 32.5 s at 10 deg/s, and the
soak compared the retained state the instant the last rotor stood at its target (16:34:23.3),
0.1 s before it stopped the bridge (SIGTERM at 16:34:23.44, too early for an "arrived" that needs
settle_s of stillness). On a half-duplex 600-baud line a poll exchange takes 0.42 s, so the last
reading before the rotor stops is up to about two exchanges of travel old: 6.5 deg here. The
bridge shows the arrival at its next reading; the soak now gives it that one poll at the end, as
it does after every recovery.

The line faults the soak had injected into that rotator shortly before (line noise while it
turned, replies cut short) were suspects too: they cost one exchange each and nothing after.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]

SOAK_SETTINGS = {"idle_poll_interval_s": 1.0, "silence_timeout_s": 3.0}  # the soak's spid
SPEED_DEG_S = 10.0
NOISE = bytes([0x8F, 0x04, 0x7E, 0xC1, 0x0A, 0xF5, 0x00, 0x95])  # no W, space, colon or digit


def soak_spid(rig: Rig) -> VirtualRotator:
    v = rig(
        "rot2prog",
        settings=SOAK_SETTINGS,
        emulator={
            "az_speed_deg_s": SPEED_DEG_S,
            "el_speed_deg_s": 5.0,
            "start_az_deg": 345.0,
            "start_el_deg": 10.0,
        },
    )
    v.run_until_state(MotionState.IDLE, 30)
    return v


def stands_at(az: float, el: float) -> Callable[[VirtualRotator], bool]:
    def there(v: VirtualRotator) -> bool:
        truth = v.truth()
        return (
            not truth.is_moving
            and truth.az_deg == pytest.approx(az)
            and truth.el_deg == pytest.approx(el)
        )

    return there


def assert_shows_the_arrival_within_one_poll(
    v: VirtualRotator, az: float, el: float, since: float
) -> None:
    """From the instant the rotor stands at az/el: the bearing it shows then is at most two
    exchanges of travel behind; the next reading shows az (one exchange plus one moving poll
    interval at most), and "arrived" follows settle_s later. Online throughout since ``since``
    (the target), and no error but the noise reported."""
    exchange_s = v.cfg.spec.exchange_time_s(v.cfg.baud)
    reading_every_s = max(exchange_s, v.cfg.moving_poll_interval_s)
    arrived_t = v.now
    shown = v.status.bearing_deg
    assert shown is not None
    assert abs(shown - az) <= SPEED_DEG_S * 2 * reading_every_s + 0.5, shown

    took = v.run_until(lambda v: v.status.bearing_deg == az, 5, f"bearing {az}")
    assert took <= exchange_s + v.cfg.moving_poll_interval_s
    assert v.status.elevation_deg == el and v.status.available

    v.run_until_state(MotionState.IDLE, 5)
    assert v.now - arrived_t <= took + v.settings.settle_s + reading_every_s + 0.1
    assert v.status.target_az_deg is None  # arrived, not stopped short
    assert all(s.available for s in v.published(since=since))
    assert not [e for e in v.errors(since=since) if e.kind != "protocol"]


def test_the_arrival_is_shown_within_one_poll_of_the_rotor_standing_there(rig: Rig) -> None:
    v = soak_spid(rig)
    t = v.now
    v.target(20, 30)
    v.run_until(stands_at(20.0, 30.0), 40, "the rotor at 20/30")
    # the soak compared the retained state at this instant: the last reading is still the one
    # taken 0.6 s before the rotor stopped
    assert v.state is MotionState.MOVING and v.status.bearing_deg != 20.0
    assert_shows_the_arrival_within_one_poll(v, 20.0, 30.0, since=t)


def test_noise_and_cut_short_replies_while_it_turns_cost_one_exchange_each(rig: Rig) -> None:
    v = soak_spid(rig)
    injected: list[bytes] = []

    def faulty_line(out: bytes, t: float) -> bytes:
        # between replies, as the soak injects them: here right before one (which the bridge
        # must then distrust: it may be spliced)
        if injected and out.startswith(b"W"):
            return injected.pop(0) + out
        return out

    v.to_host = faulty_line
    t = v.now
    v.target(20, 30)
    v.run_for(5)
    replies = b"".join(data for _, data in v.received)
    last_frame = replies[replies.rfind(b"W", 0, len(replies) - 11) :][:12]
    assert len(last_frame) == 12 and last_frame.endswith(b" ")
    # as many as the soak injects at most (four), before four replies in a row: 1.7 s without
    # a reading the bridge trusts, less than silence_timeout_s
    injected += [NOISE[:3], last_frame[:4], NOISE, last_frame[:11]]
    v.run_until(lambda v: not injected, 5, "the faults on the line")
    assert v.state is MotionState.MOVING and v.status.available
    assert v.errors("protocol"), "the noise was seen and reported"

    v.run_until(stands_at(20.0, 30.0), 40, "the rotor at 20/30")
    assert_shows_the_arrival_within_one_poll(v, 20.0, 30.0, since=t)
