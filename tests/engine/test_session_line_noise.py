"""Line noise over a reading while a rotor turns, in virtual time: an attack pass's cases on the
doubt while turning (controller.py rule 9), each a test. Before the mend a reading 20 to 200
degrees off was published."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import ErrorKind, MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
IDLE, MOVING = MotionState.IDLE, MotionState.MOVING
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}


def _flip_reply(v: VirtualRotator, after_t: float, old: bytes, new: bytes) -> list[float]:
    """The first reply after ``after_t`` that carries ``old`` has its last byte changed into
    ``new``'s (``old`` and ``new`` differ only there; the device's output comes a paced byte
    at a time) on its way to the host; the list gets when."""
    assert len(old) == len(new) and old[:-1] == new[:-1]
    buf = bytearray()
    done: list[float] = []

    def host(data: bytes, now: float) -> bytes:
        if done or now < after_t:
            return data
        buf.extend(data)
        if buf.endswith(old):
            done.append(now)
            return data[:-1] + new[-1:]
        return data

    v.to_host = host
    return done


def test_a_flipped_digit_in_the_first_reading_after_a_target_from_a_long_rest(rig: Rig) -> None:
    """The rotor rested 60 s at 100; a target 150 goes out. The reach was measured from the
    last reading that changed, 60 s before: the first reply after the target, AZ=100 read
    AZ=300, was published. It is measured from the last reading taken, or the target sent at
    rest."""
    v = rig("gs232b", emulator={"start_az_deg": 100, "start_el_deg": 10})
    v.run_until_state(IDLE, 30)
    v.run_for(60)
    t = v.now
    flipped = _flip_reply(v, t, b"AZ=1", b"AZ=3")
    v.target(150, 10)
    v.run_for(30)
    assert flipped
    shown = [s.bearing_deg for s in v.published(since=t) if s.bearing_deg is not None]
    assert max(shown) <= 160, f"published {max(shown)} while the rotor turned 100 -> 150"


def test_a_flipped_tens_digit_while_it_settles_at_its_target(rig: Rig) -> None:
    """Easycomm, 180 -> 135; at 135 the readings stop changing. One reply a second after the
    arrival read AZ115.0 (a tens digit): not published."""
    v = rig("easycomm2", emulator={**FAST, "start_az_deg": 180, "start_el_deg": 10})
    v.run_until_state(IDLE, 30)
    v.run_for(3)
    t = v.now
    v.target(135, 10)
    v.run_until(lambda h: h.truth().az_deg == 135.0 and not h.truth().is_moving, 30, "there")
    flipped = _flip_reply(v, v.now + 1.0, b"AZ13", b"AZ11")
    v.run_for(10)
    assert flipped
    shown = [s.bearing_deg for s in v.published(since=t) if s.bearing_deg is not None]
    assert min(shown) >= 130, f"published {min(shown)} with the rotor standing at 135"


def lose_readings(v: VirtualRotator, how: str) -> None:
    """The readings lost, then back: the port unplugged a second ("port"), or the replies lost
    past the silence timeout ("offline")."""
    if how == "port":
        v.link_down()
        v.run_for(1.0)
        v.link_up()
    else:
        v.set_silent(True)
        v.run_for(v.cfg.silence_timeout_s + 1)
        v.set_silent(False)


# a Rotor-EZ (a brake delay), a RotorCard (none) and a Prosistel (none, tenths); the replies
# lost for less than the silence timeout, for longer (offline), or the port unplugged a second
@pytest.mark.parametrize("lost", ["replies", "offline", "port"])
@pytest.mark.parametrize("model", ["rotorez", "rotorcard", "prosistel"])
def test_readings_lost_near_the_target_call_no_arrival_and_its_last_degrees_are_shown(
    rig: Rig, model: str, lost: str
) -> None:
    """motion.py rule 2, status.py rule 1 (a CI run): the replies of a rotor 2 degrees short of
    its target and still turning lost for longer than ``settle_s``. The clock alone called it
    arrived there, and the reading at 60 that came next was within the deadband of the 58
    shown: the status said 58 for good while the rotor stood at 60. Without a brake, the
    reading that found it arrived was not shown either (an attack pass); nor the first after
    the controller was offline, or the port back, once the way of travel was forgotten there
    (a last read)."""
    emulator = {"jitter_deg": 0, "start_az_deg": 10} if model != "prosistel" else {}
    v = rig(model, emulator=emulator)
    v.run_until_state(IDLE, 60)
    v.target(60)
    controller = v.session.controller
    v.run_until(lambda h: (controller.motion.anchor_deg or 0) >= 58, 60, "2 degrees short")
    assert v.truth().is_moving and v.truth().az_deg < 59.5
    shown = v.status.bearing_deg
    assert shown is not None and shown < 59.5
    if lost == "replies":
        v.set_silent(True)
        v.run_for(v.cfg.motion.settle_s + 0.3)  # (shorter than the silence timeout)
        assert v.status.state is MOVING and v.status.target_az_deg == 60  # no reading: no arrival
        v.set_silent(False)
    else:
        lose_readings(v, lost)
    v.run_until_state(IDLE, 30)
    v.run_for(10)
    assert v.truth().az_deg == 60 and not v.truth().is_moving
    assert v.status.bearing_deg == 60
    kinds = [e.kind for _, e in v.events]
    assert kinds == ([] if lost == "replies" else [ErrorKind.SERIAL])


def test_a_still_rotors_bearing_shown_stays_across_replugs_and_offline_spells(rig: Rig) -> None:
    """controller.py ``_lose_motion`` (an attack pass): a first reading shown as it is after
    every reconnect moved a still Rotor-EZ's bearing with its jitter, 100 to 102 and back, at
    12 of 20 replugs. Only a rotor that turned, or had a target out, when its readings were
    lost starts the bearing shown afresh."""
    v = rig("rotorez", emulator={"jitter_deg": 2, "start_az_deg": 100})
    v.run_until_state(IDLE, 60)
    v.run_for(10)
    shown = v.status.bearing_deg
    assert shown is not None and abs(shown - 100) <= 2
    for i in range(8):
        lose_readings(v, "port" if i % 2 else "offline")
        v.run_until(lambda h: h.status.available, 30, "back")
        v.run_for(2.0 + 0.37 * i)  # (the jitter's phase differs each time)
        assert v.status.bearing_deg == shown, i
    assert b";102" in b"".join(data for _, data in v.received)  # (it jittered all along)


@pytest.mark.parametrize("how", ["port", "offline"])
def test_a_still_rotor_that_last_turned_up_keeps_its_bearing_across_a_reconnect(
    rig: Rig, how: str
) -> None:
    """controller.py ``_lose_motion`` (an attack pass): the connection's first reading opens
    an assumed brake window, shown as coasting, and the way of travel kept from the last
    turn (up, long before) let a jitter reading that way through: 102 shown for good."""
    v = rig("rotorez", emulator={"jitter_deg": 0, "start_az_deg": 10})
    v.run_until_state(IDLE, 30)
    v.target(100)
    v.run_until(lambda h: h.state is IDLE and not h.truth().is_moving, 60, "at 100")
    v.run_for(10)
    assert v.status.bearing_deg == 100
    v.device.jitter_deg = 2  # the pot now reads 100, 102, 100, ... (as a real one may)
    v.run_for(30)
    assert v.status.bearing_deg == 100  # at rest: the deadband holds
    lose_readings(v, how)
    v.run_until(lambda h: h.status.available, 30, "back")
    v.run_for(10)
    assert not v.truth().is_moving and v.truth().az_deg == 100
    assert v.status.bearing_deg == 100


@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_a_new_target_while_the_reading_that_finds_the_rotor_still_is_lost_sends_no_stop(
    rig: Rig, model: str
) -> None:
    """motion.py ``plan_target`` (an attack pass): the rotor came to its target and stands
    there; the replies are lost for 2 s (less than the silence timeout) from 0.3 s after it
    stopped; a new target at 1.9 s. The motion is moving, at its target, until a reading
    finds it still: the target stopped the rotor first, a stop to a rotor at rest (the
    Rotor-EZ answers it as invalid), and waited a brake delay from it."""
    v = rig(model, emulator={"jitter_deg": 0, "start_az_deg": 10})
    v.run_until_state(IDLE, 30)
    v.target(100)
    v.run_until(lambda h: not h.truth().is_moving and abs(h.truth().az_deg - 100) < 0.5, 60)
    v.run_for(0.3)
    assert v.session.controller.motion.state is MOVING  # (the still reading not yet come)
    v.set_silent(True)
    t0 = v.now
    v.run_for(1.9)
    v.target(150)
    v.run_for(0.1)
    v.set_silent(False)
    v.run_until(lambda h: h.state is IDLE and h.truth().az_deg == 150, 60, "at 150")
    assert [w.data for w in v.writes if w.t >= t0 and w.data == b";"] == []
