"""A rotor that turns on past its target (motion.py rule 5, stops.py rules 3 and 4), in virtual
time with the emulators: the cases a review of the first form found, each of which failed on it.
What a user notices: whether the rotor turns on, is stopped, and what the error says."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState, Target
from bridge.protocols.axes import Axis
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite

Rig = Callable[..., VirtualRotator]
IDLE = MotionState.IDLE


def online(v: VirtualRotator) -> VirtualRotator:
    v.run_until(lambda h: h.status.available and h.state is IDLE, 30, "online")
    return v


def passed(v: VirtualRotator) -> bool:
    return any("past its target" in e.message for e in v.errors())


def test_a_flicker_of_one_count_is_no_arrival_before_a_move_across_the_stop(rig: Rig) -> None:
    """A GS-232 at 357 sent to 1 goes the long way down; the reply to the poll written just
    before the target flickered to 358, closer to 1 but within the noise: no movement, so no
    arrival, and the long turn is not taken for a pass and stopped."""
    v = online(rig("gs232b-az", emulator={"start_az_deg": 357.0}))
    v.run_for(3)
    n = len(v.writes)
    v.run_until(lambda h: len(h.writes) > n and h.writes[-1].data == b"C\r", 5, "poll out")
    once = {"on": True}

    def flicker(data: bytes, now: float) -> bytes:  # that poll's reply: 357 -> 358
        if once["on"] and data == b"7":
            once["on"] = False
            return b"8"
        return data

    v.to_host = flicker
    v.target(1.0)
    v.run_for(20)
    assert not passed(v) and v.truth().is_moving, (v.truth(), v.errors())


def test_one_flipped_bit_after_an_idle_spell_is_no_arrival(rig: Rig) -> None:
    """At rest for 20 s, then sent the long way: the first reading after the target has one
    bit flipped (349 read 149, over the target from 350). The rotor cannot have turned that
    far since the target went out: no pass, and the turn goes on."""
    v = online(rig("gs232b-az", emulator={"start_az_deg": 340.0}))
    v.target(350.0)
    v.run_until(lambda h: h.state is IDLE and h.truth().az_deg == 350.0, 60, "at 350")
    v.run_for(20)
    st = {"on": True, "tail": b""}

    def flip(data: bytes, now: float) -> bytes:  # the first "AZ=3.." -> "AZ=1.."
        out = bytearray()
        for b in data:
            st["tail"] = (st["tail"] + bytes([b]))[-4:]
            out.append(ord("1") if st["on"] and st["tail"] == b"AZ=3" else b)
            st["on"] = st["on"] and st["tail"] != b"AZ=3"
        return bytes(out)

    v.to_host = flip
    v.target(10.0)
    v.run_for(15)
    assert not passed(v) and v.truth().is_moving, (v.truth(), v.errors())


def test_a_stop_owed_to_a_silence_after_a_heard_target_is_said(rig: Rig) -> None:
    """stops.py rule 3, the safe side: STOP, a target 0.1 s later, both heard, and the replies
    lost before two readings came: no reading shows that target taken, so the stop is owed
    and cuts the move short when the controller answers again; the error says so."""
    v = online(rig("gs232b-az"))
    v.target(300.0)
    v.run_until(lambda h: h.truth().az_deg > 220, 60, "past 220")
    v.stop()
    v.run_for(0.1)
    v.target(100.0)
    v.run_for(0.1)
    v.set_silent(True)  # it hears and turns to 100; its replies are lost
    v.run_until(lambda h: not h.status.available, 10, "offline")
    assert any("the last stop" in e.message for e in v.errors()), v.errors()
    v.set_silent(False)
    v.run_until(lambda h: h.status.available, 10, "online again")
    v.run_until(lambda h: not h.truth().is_moving, 60, "at rest")
    assert abs(v.truth().az_deg - 100.0) > 10, v.truth()


def test_a_hand_at_the_panel_right_after_an_arrival_is_stopped_once_not_fought(
    rig: Rig,
) -> None:
    """The pass's stop is written once and not checked (stops.py rule 4): an operator holding
    the panel button in the settle time after an arrival is stopped once, not every 2 s."""
    v = online(rig("gs232b-az"))
    v.target(100.0)
    v.run_until(lambda h: not h.truth().is_moving and h.truth().az_deg == 100.0, 60, "at 100")
    v.run_for(0.4)  # in the settle time
    t = v.now
    v.manual_rotate(250.0)  # the operator holds the panel button
    end = v.now + 20
    while v.now < end:
        v.run_for(0.05)
        if not v.truth().is_moving and v.truth().az_deg < 250.0:
            v.manual_rotate(250.0)  # still held
    stops = v.sent(since=t).count(b"S\r")
    assert stops <= 1, (stops, [e.message for e in v.errors()])


def lost_stop_and_target(v: VirtualRotator | VirtualComposite, target: Callable[[], None]) -> None:
    """A STOP and the target after it, both lost in a burst too short to be found silent."""
    boxes = v.boxes.values() if isinstance(v, VirtualComposite) else [v]
    for box in boxes:
        box.set_deaf(True)
    v.run_for(0.3)
    v.stop()
    v.run_for(0.3)
    target()
    v.run_for(1.0)
    for box in boxes:
        box.set_deaf(False)


def test_an_az_el_box_passing_its_azimuth_while_its_elevation_climbs_on_is_stopped(
    rig: Rig,
) -> None:
    """Either axis that comes to its target counts: a GS-232B passing azimuth 100 while its
    elevation still climbs to the old 60 (the new one, 10, lost with the STOP) ran on."""
    v = online(rig("gs232b"))
    v.target(300.0, 60.0)
    v.run_until(lambda h: h.truth().az_deg > 40, 60, "past 40")
    lost_stop_and_target(v, lambda: v.target(100.0, 10.0))
    v.run_until(lambda h: h.truth().az_deg > 100.0, 60, "past 100")
    v.run_for(10)
    assert v.truth().az_deg < 130.0 and not v.truth().is_moving, (v.truth(), v.errors())


def test_a_composites_elevation_box_passing_its_target_is_stopped() -> None:
    """The elevation box of a composite echoes the azimuth: its own axis passing the new
    elevation counts. Before, the azimuth box was stopped and the elevation box ran on to the
    60 the operator had stopped."""
    fast = {
        Axis.AZIMUTH: {"az_speed_deg_s": 6.0},
        Axis.ELEVATION: {"az_speed_deg_s": 6.0, "el_speed_deg_s": 2.5},
    }
    with VirtualComposite("rt21", "gs232b", emulators=fast) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(200.0, 60.0))
        v.run_until(lambda h: h.status.state is MotionState.MOVING, 5, "moving")
        v.run_for(2.0)
        lost_stop_and_target(v, lambda: v.aim(Target(100.0, 10.0)))
        v.run_for(40)
        az, el = v.az.truth().az_deg, v.el.truth().el_deg
        assert az < 130.0 and el < 30.0, (az, el)
