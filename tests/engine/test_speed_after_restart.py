"""A GS-232 set to its slowest speed (``speed`` 1, ``X1``) comes back from a power cycle at its
fastest (``X4``: emulators/gs232.py rule 5) and says nothing about it. The speed the user chose
for a heavy array is sent again before the next turn whenever the bridge has a sign that the box
may have restarted: a stall that names a restart (controller.py rule 12), or a reply that never
came (options.py rule 1). An attack pass found the next target sent alone, the rotor turning at
four times the chosen speed until the idle refresh, up to a minute later."""

from __future__ import annotations

import pytest

from bridge.core.model import ErrorKind, MotionState
from tests.engine.virtual import VirtualRotator

MODELS = ["gs232b-az", "gs232a"]


def slow(v: VirtualRotator) -> float:
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
    v.option("speed", "1")
    v.run_for(2.0)
    assert v.truth().speed_level == 1  # X1 went out and was taken
    return v.now


def turn_after(v: VirtualRotator, t: float) -> list[bytes]:
    """A target now: the box's speed level as it turns, and the frames other than polls sent
    since ``t``."""
    v.target(300.0)
    v.run_until(lambda h: h.truth().is_moving, 10, "turning again")
    v.run_for(3.0)
    return [w.data for w in v.writes if w.t >= t and not w.data.startswith(b"C")]


def speed_first(sent: list[bytes]) -> bool:
    """The speed written before the target (``M300``, or ``W300 ...`` on an az/el box)."""
    turn = next(i for i, f in enumerate(sent) if f.startswith((b"M300", b"W300")))
    return b"X1\r" in sent[:turn]


@pytest.mark.parametrize("model", MODELS)
def test_the_speed_goes_again_before_the_turn_after_a_stall_that_may_be_a_restart(
    model: str,
) -> None:
    with VirtualRotator(model) as v:
        slow(v)
        v.target(100.0)
        v.run_until(lambda h: h.truth().az_deg > 20, 90, "turning")
        t = v.now
        v.power_cycle()  # mid-turn, instantly: the rotor stands, the box forgets X1
        v.run_until(lambda h: h.errors(ErrorKind.STALLED, since=t), 30, "the stall said")
        said = v.errors(ErrorKind.STALLED, since=t)[0].message
        assert "or the controller restarted (power cycled or reset)" in said
        v.run_for(0.1)
        sent = turn_after(v, t)
        assert v.truth().speed_level == 1, sent
        assert speed_first(sent), sent


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("off_s", [1.0, 2.5])
def test_the_speed_goes_again_before_the_turn_after_a_power_cycle_at_rest(
    model: str, off_s: float
) -> None:
    """Off long enough to leave a poll unanswered, back before the bridge calls it offline: no
    error is said, yet the target waits for the box's answer and the speed goes first."""
    with VirtualRotator(model) as v:
        t = slow(v)
        v.set_silent(True)
        v.set_deaf(True)
        v.run_for(off_s)
        v.power_cycle()
        v.set_silent(False)
        v.set_deaf(False)
        v.run_for(1.5)
        sent = turn_after(v, t)
        assert v.truth().speed_level == 1, sent
        assert speed_first(sent), sent
        assert v.errors(since=t) == []


def test_a_reply_lost_costs_no_setting_when_none_is_set() -> None:
    """Nothing set: a reply lost sends no setting, and the target goes as ever."""
    with VirtualRotator("gs232b-az") as v:
        v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
        t = v.now
        v.set_silent(True)
        v.run_for(2.5)
        v.set_silent(False)
        v.target(300.0)
        v.run_until(lambda h: h.truth().is_moving, 10, "turning")
        assert [w.data for w in v.writes if w.t >= t and w.data != b"C\r"] == [b"M300\r"]
        assert v.errors(since=t) == []
