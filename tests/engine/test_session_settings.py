"""A controller setting in virtual time (session/options.py): a GS-232's speed goes out when its
declaration allows (any time the line is free: the box applies it to the turn in progress), the
rotor turns at the new speed and the engine expects that speed, and the setting is sent again
after the box was switched off and on (it forgets it) and after a reconnect."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState, SetOption, Stop
from bridge.emulators.gs232 import Outcome
from bridge.session.options import OPTIONS_REFRESH_S
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}


def ready(rig: Rig, **kw: object) -> VirtualRotator:
    v = rig("gs232b", emulator=FAST, **kw)
    v.run_until_state(IDLE, 30)
    v.run_for(1.0)  # what is owed at the first answer is on the wire and heard
    return v


def speeds(v: VirtualRotator) -> list[bytes]:
    return [f.data for f in v.frames(Outcome.SPEED)]


def turned_in(v: VirtualRotator, seconds: float) -> float:
    start = v.truth().az_deg
    v.run_for(seconds)
    return v.truth().az_deg - start


def test_a_speed_set_while_turning_goes_out_at_once_and_slows_the_turn(rig: Rig) -> None:
    v = ready(rig)
    assert speeds(v) == [] and v.truth().speed_level == 4  # nothing set: the box's own
    v.target(350, 0)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 10, 30, "turning")
    before = turned_in(v, 5.0)
    t = v.now
    v.option("speed", "2")
    v.run_until(lambda h: speeds(h), 1, "X2 on the wire")
    assert b"X2\r" in v.sent(since=t) and speeds(v) == [b"X2"]
    assert v.truth().is_moving and v.truth().speed_level == 2  # not held back until rest
    after = turned_in(v, 5.0)
    assert 0.45 < after / before < 0.55  # half the speed: X2 of X4
    # the engine's motion model expects what the box now does (controller.py rule 7)
    assert v.session.controller.cfg.az_speed_deg_s == 3.0
    assert v.status.options == {"speed": "2"} and v.errors() == []


def test_the_speed_is_sent_again_after_the_box_was_switched_off_and_on(rig: Rig) -> None:
    v = ready(rig, options={"speed": "1"})
    assert speeds(v) == [b"X1"] and v.truth().speed_level == 1  # once it answers
    v.power_cycle()  # no power-on byte on a GS-232: the box is at X4 again, unseen
    assert v.truth().speed_level == 4
    t = v.now
    v.run_until(lambda h: h.truth().speed_level == 1, OPTIONS_REFRESH_S + 5, "X1 again")
    assert v.sent(since=t).count(b"X1\r") == 1


def test_the_speed_is_sent_again_after_a_reconnect(rig: Rig) -> None:
    v = ready(rig, options={"speed": "3"})
    v.link_down()
    v.power_cycle()
    v.link_up()
    t = v.now
    v.run_until(lambda h: h.truth().speed_level == 3, 10, "X3 after the reconnect")
    assert v.sent(since=t).count(b"X3\r") == 1
    assert v.session.controller.cfg.az_speed_deg_s == 4.5  # three quarters of 6


def test_rotor_health_measures_the_full_speed_whatever_speed_the_user_chose(rig: Rig) -> None:
    """A rotor turned at X2 is no rotor that lost half its speed (health.py rule 9)."""
    v = ready(rig, options={"speed": "2"}, settings={"az_speed_deg_s": 6.0})  # the baseline
    for az in (120, 10, 200, 30, 150, 40):  # three moves each way: enough to judge by
        v.target(az, 0)
        v.run_until(lambda h, az=az: h.truth().az_deg == az and h.state is IDLE, 120, f"at {az}")
    assert v.truth().speed_level == 2
    health = v.status.health
    assert health is not None and health.az is not None
    assert health.az.speed_up_deg_s is not None and health.az.speed_down_deg_s is not None
    assert 5.0 < health.az.speed_up_deg_s < 7.0 and 5.0 < health.az.speed_down_deg_s < 7.0
    assert health.warnings == ()


def test_a_stop_with_a_speed_in_the_same_instant_goes_out_first(rig: Rig) -> None:
    """A stop is never delayed (docs/architecture.md rule 11): not by a setting either."""
    v = ready(rig)
    v.target(300, 0)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 10, 30, "turning")
    t = v.now
    v.command(Stop(), SetOption("speed", "1"))
    v.run_until(lambda h: speeds(h), 1, "X1 on the wire")
    sent = v.sent(since=t)
    assert sent.index(b"S\r") < sent.index(b"X1\r")


def test_a_flood_of_speeds_puts_a_few_on_the_wire_and_the_last_one_wins(rig: Rig) -> None:
    """Anyone who may publish R/option/speed can send hundreds a second: each went to the box
    as its own X command (15,315 of the 15,458 frames on the wire in 35 s through mosquitto,
    the polls crowded out, an INFO line each). A setting goes out at most once per
    SETTING_GAP_S, the last value set meanwhile; the turn and a stop go on as without it."""
    from bridge.session.options import SETTING_GAP_S

    v = ready(rig)
    v.target(300, 0)
    v.run_until(lambda h: h.state is MOVING and h.truth().az_deg > 10, 30, "turning")
    t = v.now
    for i in range(2000):  # 10 s of words every 5 ms, the same value twice in a row
        v.option("speed", "1" if (i // 2) % 2 else "4")
        v.run_for(0.005)
    v.option("speed", "3")
    flood_s = v.now - t
    v.run_for(2 * SETTING_GAP_S)
    sent = [d for d in v.sent(since=t) if d.startswith(b"X")]
    assert len(sent) <= flood_s / SETTING_GAP_S + 2, len(sent)
    assert sent[-1] == b"X3\r" and v.truth().speed_level == 3
    v.stop()
    stopped_at = v.now
    v.run_until(lambda h: not h.truth().is_moving, 2, "stopped")
    assert v.frames(Outcome.STOP, since=stopped_at)
    assert v.errors() == []


def test_a_setting_shows_in_the_status_at_once_though_it_waits_to_go_out(rig: Rig) -> None:
    """The status is built again only when something it shows changed (session.py rule 18): a
    value set while the one before still holds the line's gap (options.py rule 4) changes
    nothing else, and is shown all the same."""
    v = ready(rig)
    v.option("speed", "2")
    v.run_until(lambda h: speeds(h), 1, "X2 on the wire")
    v.option("speed", "3")  # within the gap: it waits, the rotor at rest, nothing else new
    v.run_for(0.1)
    assert speeds(v) == [b"X2"]
    assert v.status.options == {"speed": "3"}
