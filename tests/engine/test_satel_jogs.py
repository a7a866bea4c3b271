"""The SatEL's own frames are each one flipped bit from a jog that runs until it is told
otherwise (``z`` 0x7A and ``s`` 0x73 from ``r`` 0x72, azimuth clockwise; ``t`` 0x74 from ``u``
0x75, elevation up): an attack pass ran it past ``az_max_deg`` and ``el_max_deg`` to its end
stops, followed and unsaid. Its ``unasked_moves`` is "stop" (controller.py rule 10): such a
turn is stopped a few degrees on, with a ``stop`` error. Virtual time, the project's emulator;
what is asserted is where the emulated rotor went."""

from __future__ import annotations

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

START = {"start_az_deg": 100, "start_el_deg": 10}


def highest(v: VirtualRotator, seconds: float, el: bool = False) -> float:
    end, top = v.now + seconds, -1.0
    while v.now < end:
        v.run_for(0.1)
        t = v.truth()
        top = max(top, t.el_deg if el else t.az_deg)
    return top


def stopped_says(v: VirtualRotator) -> list[str]:
    return [e.message for e in v.errors() if "no command from the bridge" in e.message]


def test_an_idle_poll_garbled_into_a_jog_is_stopped() -> None:
    v = VirtualRotator("satel", settings={"az_max_deg": 300}, emulator=START)
    v.run_until_state(MotionState.IDLE, 60)
    v.run_for(5)
    v.garble_writes(b"z", b"r")
    assert highest(v, 90) < 130  # not to 300 and on to the end stop
    assert stopped_says(v)


def test_the_clock_line_at_connect_garbled_into_a_jog_up_is_stopped() -> None:
    v = VirtualRotator("satel", settings={"el_max_deg": 45}, emulator=START, connect=False)
    v.to_device = lambda data, now: b"u" + data[1:] if data.startswith(b"t20") else data
    v.link_up()
    assert highest(v, 60, el=True) < 30
    assert stopped_says(v)


def test_the_opening_stop_garbled_into_a_jog_is_stopped() -> None:
    """The ``s`` that opens the connection, read as ``r``: no report answers it, so it is
    written again (session/link.py rule 14, as a stop lost on the line), and that stop ends
    the jog a few degrees on, before the rest of the connect goes."""
    v = VirtualRotator("satel", settings={"az_max_deg": 300}, emulator=START, connect=False)
    v.garble_writes(b"s", b"r")
    v.link_up()
    assert highest(v, 60) < 110
    assert not v.truth().is_moving
    assert [w.data for w in v.writes[:3]] == [b"s", b"s", b"s"]  # (the first garbled)
