"""The storm's park and the offline stop (wind.py rule 7, runtime/composite.py rule 8): a
controller that goes offline mid-park is stopped (session/controller.py rule 2), and its park
is sent again once it answers; on a rotator of two boxes, the other box's park goes on. (A
review of d35d250 and 83a398d: after 4 s of lost replies, the park stood 140 degrees short for
the whole storm, and nobody could send it again: motion is refused in a storm.)"""

from __future__ import annotations

from bridge.core.model import MotionState, Target
from bridge.protocols.axes import Axis
from bridge.session.motion import blind_busy_s
from tests.engine.test_wind import wind, windy
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite

FAST = {
    Axis.AZIMUTH: {"az_speed_deg_s": 6.0},
    Axis.ELEVATION: {"az_speed_deg_s": 6.0, "el_speed_deg_s": 2.5},
}
WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180, "park_el_deg": 0}


def parking() -> VirtualRotator:
    """A GS-232B at rest at 10 / 30, its wind park at 180 / 0."""
    v = VirtualRotator("gs232b", settings=WIND, emulator={"az_speed_deg_s": 6.0})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
    v.target(10.0, 30.0)
    v.run_until(lambda h: abs(h.truth().az_deg - 10) < 1, 120, "at 10")
    return v


def storm(v: VirtualRotator) -> None:
    """A storm begins; two seconds into its park."""
    v.mailbox.put_wind(90.0)
    v._take()
    v.run_for(2.0)


def at_10_30(v: VirtualComposite) -> None:
    """Both boxes answering, the rotor at rest at 10/30 (before the storm)."""
    v.run_until(lambda h: h.status.available, 10, "both boxes answer")
    v.aim(Target(10.0, 30.0))
    v.run_until(
        lambda h: abs(h.az.truth().az_deg - 10) < 1 and abs(h.el.truth().el_deg - 30) < 1,
        120,
        "at 10/30",
    )


def test_composite_storm_park_survives_a_short_silence_of_the_elevation_box() -> None:
    with VirtualComposite("rt21", "gs232b", settings=WIND, emulators=FAST) as v:
        at_10_30(v)
        v.mailbox.put_wind(90.0)
        v._take()
        v.run_for(2.0)
        assert v.az.truth().is_moving
        v.el.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "offline")
        v.run_for(1.0)
        v.el.set_silent(False)
        v.run_until(lambda h: h.status.available, 20, "back")
        v.run_for(120.0)
        assert v.status.wind is not None and v.status.wind.storm
        assert abs(v.az.truth().az_deg - 180.0) < 1.0, v.az.truth()
        assert abs(v.el.truth().el_deg) < 1.0, v.el.truth()  # (its own park, owed again)


def test_composite_storm_park_waiting_in_the_brake_delay_survives_the_other_box_offline() -> None:
    """A Rotor-EZ azimuth box turning when the storm begins: a stop first, the park waits out
    the brake delay; the elevation box falls silent meanwhile. The park still goes (an attack
    pass: it was dropped there, and the antenna stood 150 degrees short of it all storm)."""
    az_box = {Axis.AZIMUTH: {"speed_deg_s": 6.0}, Axis.ELEVATION: FAST[Axis.ELEVATION]}
    with VirtualComposite("rotorez", "gs232b", settings=WIND, emulators=az_box) as v:
        at_10_30(v)
        v.aim(Target(300.0, 30.0))
        v.run_until(lambda h: h.az.truth().az_deg > 20, 30, "turning toward 300")
        v.mailbox.put_wind(90.0)
        v._take()
        v.el.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "offline")
        assert v.az.truth().in_brake_delay  # (the park still waiting when the box went out)
        v.el.set_silent(False)
        v.run_until(lambda h: h.status.available, 20, "back")
        v.run_for(120.0)
        assert v.status.wind is not None and v.status.wind.storm
        assert abs(v.az.truth().az_deg - 180.0) < 1.0, v.az.truth()
        assert abs(v.el.truth().el_deg) < 1.0, v.el.truth()


def test_single_storm_park_survives_a_short_silence() -> None:
    v = parking()
    try:
        v.run_for(5)
        storm(v)
        assert v.truth().is_moving
        v.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "offline")
        v.run_for(1.0)
        v.set_silent(False)
        v.run_until(lambda h: h.status.available, 20, "back")
        v.run_for(120.0)
        assert v.status.wind is not None and v.status.wind.storm
        assert abs(v.truth().az_deg - 180.0) < 1.0, (v.truth(), [e.message for e in v.errors()])
    finally:
        v.close()


def test_a_park_stopped_by_the_operator_is_not_sent_again_after_an_offline() -> None:
    """wind.py rule 3 holds: the operator's STOP in the storm, then a silence: no park again."""
    v = parking()
    try:
        storm(v)
        v.stop()
        v.run_for(2.0)
        az = v.truth().az_deg
        v.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "offline")
        v.set_silent(False)
        v.run_until(lambda h: h.status.available, 20, "back")
        v.run_for(60.0)
        assert abs(v.truth().az_deg - az) < 1.0, v.truth()
    finally:
        v.close()


def test_a_park_unplugged_mid_turn_is_finished_after_the_replug() -> None:
    v = parking()
    try:
        storm(v)
        v.link_down()
        v.power_cycle()  # (the controller lost its power with the line: the turn ended)
        v.run_for(5.0)
        v.link_up()
        v.run_until(lambda h: h.status.available, 20, "back")
        v.run_for(120.0)
        assert abs(v.truth().az_deg - 180.0) < 1.0, v.truth()
    finally:
        v.close()


def parked_then_turned_by_hand(v: VirtualRotator) -> None:
    """A storm; the rotor parked for it, then turned at its front panel to 250, at rest."""
    wind(v, 90.0)
    v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
    v.manual_rotate(250.0)
    v.run_until(lambda h: abs(h.truth().az_deg - 250.0) < 1, 60, "turned by hand")
    v.run_until(lambda h: h.state is MotionState.IDLE, 30, "at rest")


def test_a_park_reached_and_turned_away_by_hand_is_not_sent_again_after_an_offline() -> None:
    """wind.py rule 7 owes only a park the line took: one the rotor reached is done. An MD-01
    turned at its front panel afterwards, then 3 s of silence: the rotor stays where the hand
    left it (an attack pass: it was turned back to the park by itself once it answered)."""
    with windy() as v:
        parked_then_turned_by_hand(v)
        v.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "offline")
        v.set_silent(False)
        v.run_until(lambda h: h.status.available, 20, "back")
        v.run_for(60.0)
        assert v.status.wind is not None and v.status.wind.storm
        assert abs(v.truth().az_deg - 250.0) < 1.0, v.truth()


def test_a_dcu1_park_never_seen_is_sent_again_after_the_port_comes_back() -> None:
    """wind.py rule 7: a DCU-1 cannot report where it stands, so its storm park is never seen
    reached (``parked`` only says its estimated move is over). Its adapter wedged when the
    storm began (the park never reached the controller), the operator unplugs it and plugs it
    in again: the park goes again and the antenna ends at the park, as before the rule."""
    settings = {k: w for k, w in WIND.items() if k != "park_el_deg"}  # (azimuth only)
    v = VirtualRotator("dcu1", settings=settings, emulator={"start_az_deg": 30})
    try:
        cfg = v.cfg.motion
        v.run_for(blind_busy_s(cfg.az_span_deg, cfg) + cfg.brake_delay_s + 1)
        v.set_deaf(True)  # (a wedged adapter: what the bridge writes never arrives)
        storm(v)
        v.run_until(lambda h: h.status.parked, 120, "the park's estimated move over")
        wind(v, 85.0)  # (the storm's next reading)
        v.run_for(60.0)
        assert abs(v.truth().az_deg - 30.0) < 1.0  # (it never heard the park)
        v.link_down()
        v.set_deaf(False)
        v.link_up()
        v.run_for(120.0)
        assert v.status.wind is not None and v.status.wind.storm
        assert abs(v.truth().az_deg - 180.0) < 1.0, v.truth()
    finally:
        v.close()


def test_a_storm_known_only_from_a_replay_parks_nothing_after_an_offline() -> None:
    """wind.py rule 6 beside rule 7: a storm the broker replayed refuses motion and parks
    nothing; a short silence of the controller then owed "its park" (one never sent) and sent
    it once the controller answered: a replayed reading turned the rotor."""
    v = parking()
    try:
        v.mailbox.put_wind(90.0, replayed=True)
        v._take()
        v.run_for(2.0)
        assert v.status.wind is not None and v.status.wind.storm and v.status.wind.replayed
        v.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "offline")
        v.set_silent(False)
        v.run_until(lambda h: h.status.available, 20, "back")
        v.run_for(60.0)
        assert abs(v.truth().az_deg - 10.0) < 1.0, v.truth()  # not turned to the park, 180
        assert v.status.wind is not None and v.status.wind.replayed
    finally:
        v.close()
