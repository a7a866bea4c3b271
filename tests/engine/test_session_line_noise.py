"""Line noise over a reading while a rotor turns, in virtual time: an attack pass's cases on the
doubt while turning (controller.py rule 9), each a test. Before the mend a reading 20 to 200
degrees off was published."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
IDLE = MotionState.IDLE
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
