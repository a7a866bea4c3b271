"""A composite rotator's own moves (runtime/composite.py rule 7, app.py ``axis_configs``): the
storm's park and auto-park turn both boxes, each its own axis, and auto-park's quiet spell is
the rotator's, not a box's: an operator working one axis never has the other parked under
them. In virtual time, an RT-21 on the azimuth and a GS-232B used for its elevation."""

from __future__ import annotations

from bridge.core.model import MotionState, Source, Target
from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite

FAST = {
    Axis.AZIMUTH: {"az_speed_deg_s": 6.0},
    Axis.ELEVATION: {"az_speed_deg_s": 6.0, "el_speed_deg_s": 2.5},
}
STOW = {"park_az_deg": 180, "park_el_deg": 0}  # a dish's stow: an elevation with the park


def there(v: VirtualComposite, az: float, el: float) -> bool:
    return abs(v.az.truth().az_deg - az) < 1.0 and abs(v.el.truth().el_deg - el) < 1.0


def aimed(settings: dict[str, object]) -> VirtualComposite:
    v = VirtualComposite("rt21", "gs232b", settings=settings, emulators=FAST)
    v.run_until(lambda h: h.status.available, 10, "both boxes answer")
    v.aim(Target(100.0, 30.0))
    v.run_until(lambda h: there(h, 100.0, 30.0), 60, "at 100/30")
    return v


def test_a_storm_parks_both_axes_of_a_stow_position() -> None:
    """Judged by the azimuth box with the park's elevation, the storm's park was refused there
    ("RT-21 has no elevation axis"): the dish stowed its elevation and kept facing the storm."""
    wind = {"wind_topic": "weather/wind", "wind_park_above": 60, **STOW}
    with aimed(wind) as v:
        t = v.now
        v.mailbox.put_wind(90.0)
        v._take()
        v.run_until(lambda h: there(h, 180.0, 0.0), 300, "both axes at the wind park")
        assert v.status.wind is not None and v.status.wind.storm
        assert [e.message for e in [*v.az.errors(), *v.el.errors()] if e.kind == "refused"] == []
        assert v.az.published(since=t)[-1].last_command_source == "wind"


def test_auto_park_parks_both_axes_together_once_the_rotator_was_left_alone() -> None:
    with aimed({"park_after_idle_s": 120, **STOW}) as v:
        start = v.now
        v.run_until(lambda h: there(h, 180.0, 0.0), 400, "both axes parked")
        assert 120 <= v.now - start <= 200
        assert [e.message for e in [*v.az.errors(), *v.el.errors()] if e.kind == "refused"] == []


def test_working_the_elevation_alone_never_parks_the_azimuth() -> None:
    """An elevation tweak every 30 s (the moon climbs): each was no command to the azimuth box,
    whose own quiet spell then parked its axis under the operator."""
    with aimed({"park_after_idle_s": 120, "park_az_deg": 180}) as v:
        for step in range(1, 11):
            v.run_for(30.0)
            v.aim(Target(None, 30.0 + step))
        assert abs(v.az.truth().az_deg - 100.0) < 1.0
        assert v.status.last_command_source != "auto-park"


def test_working_the_azimuth_alone_never_parks_the_elevation() -> None:
    with aimed({"park_after_idle_s": 120, **STOW}) as v:
        for step in range(1, 11):
            v.run_for(30.0)
            v.aim(Target(100.0 + 2 * step, None))
        assert abs(v.el.truth().el_deg - 30.0) < 1.0


def test_a_hand_on_one_box_keeps_the_other_from_parking() -> None:
    """autopark.py rule 1 for the rotator: the azimuth turned at its front panel, again and
    again, is activity of the rotator; its elevation is not parked meanwhile."""
    with aimed({"park_after_idle_s": 120, **STOW}) as v:
        for step in range(1, 8):
            v.run_for(30.0)
            v.az.manual_rotate(100.0 + 10 * (step % 2))
        assert abs(v.el.truth().el_deg - 30.0) < 1.0


def test_no_box_parks_its_axis_while_the_other_does_not_answer() -> None:
    """Rule 7: the rotator is offline (targets refused); the azimuth box parked by itself all
    the same. Once both answer, the quiet spell starts again."""
    with aimed({"park_after_idle_s": 120, **STOW}) as v:
        v.el.set_silent(True)  # the elevation box stops answering (unplugged, powered off)
        v.run_until(lambda h: h.status.state is MotionState.OFFLINE, 60, "offline")
        t = v.now
        v.run_for(300)
        assert v.az.frames("move", since=t) == []
        v.el.set_silent(False)
        v.run_until(lambda h: h.status.available, 30, "both answer again")
        back = v.now
        v.run_until(lambda h: there(h, 180.0, 0.0), 400, "both axes parked")
        assert v.now - back >= 120


def test_a_hand_on_the_azimuth_as_the_spell_ends_does_not_park_the_elevation_alone() -> None:
    """DEFECT: a hand on the azimuth box's front panel begun between its last idle poll and the
    end of the quiet spell. The Rotor-EZ asks first and dropped its park (autopark.py rule 3);
    the GS-232B sends its park at once, and the elevation went on to its stow under the hand,
    the azimuth parked a whole spell later: the rotator was parked one axis at a time. Now the
    elevation's park is stopped as soon as the hand is seen (rule 4), the azimuth's hand is not
    cut short, and both axes park together a whole quiet spell after the hand's last move."""
    emulators = {
        Axis.AZIMUTH: {"speed_deg_s": 6.0, "jitter_deg": 0},
        Axis.ELEVATION: FAST[Axis.ELEVATION],
    }
    settings = {"park_after_idle_s": 60, "idle_poll_interval_s": 4, **STOW}
    with VirtualComposite("rotorez", "gs232b", settings=settings, emulators=emulators) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(100.0, 30.0))
        v.run_until(lambda h: there(h, 100.0, 30.0), 60, "at 100/30")
        v.run_until(lambda h: h.status.state is MotionState.IDLE, 30, "at rest")
        deadline = v.az.session.autopark.deadline()
        assert deadline is not None
        v.run_for(deadline - 0.5 - v.now)  # after the azimuth box's last idle poll
        t_hand = v.now
        v.az.manual_rotate(250.0)  # unseen till the reading asked for the azimuth's park
        v.run_until(lambda h: abs(h.az.truth().az_deg - 250.0) < 1.0, 60, "the hand's turn done")
        assert v.el.truth().el_deg > 28.0  # the elevation was not parked under the hand
        v.run_until(lambda h: there(h, 180.0, 0.0), 300, "both axes parked")
        asked = next(w.t for w in v.az.writes if w.t >= t_hand and w.data == b"AI1;")
        assert asked >= deadline  # (the race: no idle poll saw the hand before the spell ended)
        assert b";" not in v.az.sent(since=t_hand), v.az.sent(since=t_hand)
        hand = [e for e in v.az.device.events if e.time_s >= t_hand and e.kind == "arrived"][0]
        assert hand.az_deg == 250.0  # the hand's turn ran to its end
        el = [e for e in v.el.device.events if e.time_s >= t_hand]
        assert [e.kind for e in el[:2]] == ["move", "stopped"], el
        assert el[1].time_s - el[0].time_s < 1.0, el  # its park stopped at once
        az_parks = [f.time_s for f in v.az.frames(since=t_hand) if f.data.startswith(b"AP1")]
        el_parks = [f.time_s for f in v.el.frames("move", since=el[1].time_s)]
        assert min(az_parks + el_parks) - hand.time_s >= 60, "parked before a quiet spell"
        assert abs(az_parks[0] - el_parks[0]) < 1.0  # together (rule 4)
        assert [*v.az.errors(), *v.el.errors()] == []


def test_a_park_naming_no_elevation_holds_the_elevation_box_where_it_reads() -> None:
    """session/targets.py rule 9 for R/park (no ``park_el_deg``): the park takes the place of
    the turn it finds, an axis it leaves out held where it reads, as one GS-232B does alone.
    An attack pass: the elevation box got no half of the park (``split``: an axis a target
    leaves out is no target for that box) and turned on from 10 to the 40 of the 100/40 the
    park interrupted, and the rotator never said parked (both boxes' ``parked``)."""
    with VirtualComposite("rt21", "gs232b", settings={"park_az_deg": 180}, emulators=FAST) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(100.0, 40.0))
        v.run_until(lambda h: h.el.truth().el_deg >= 10.0, 60, "the elevation under way")
        t = v.now
        v.aim(Target(180.0, None, Source.MQTT, park=True))  # R/park, judged (pointing.py)
        v.run_until(lambda h: abs(h.az.truth().az_deg - 180.0) < 1.0, 200, "the azimuth parked")
        v.run_for(30.0)
        assert not any(w.endswith(b" 040\r") for w in v.el.sent(since=t)), v.el.sent(since=t)
        assert 10.0 <= v.el.truth().el_deg <= 14.0, v.el.truth()
        assert abs(v.az.truth().az_deg - 180.0) < 1.0
        assert v.status.parked
