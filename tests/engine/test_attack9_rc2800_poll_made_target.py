"""Attack 9: an RC2800's poll is its axis letter alone (``A`` CR), and a target is the letter and
a bearing (``A123.4`` CR): one stray byte on the line (a digit) makes a poll a target. The
turn it starts is a turn nobody asked for: followed, with ``unasked_moves`` "follow", whatever
the user's limits say (the motion machine watches a limit only while a target of the bridge's
is out, motion.py rule 10), and nothing said; the rotor ran from 150 to 5, past az_min_deg 30.
The Easycomm's poll, one flipped bit from a jog, made "stop" its default for the same reason
(an attack soak ran a rotor to its end stop); the RC2800's is "stop" now too (rc2800.py rule 8,
session/controller.py rule 10): such a turn is stopped 5 degrees from where the rotor rested,
and a ``stop`` error says why."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.parametrize("model", ["rc2800", "rc2800-az"])
def test_a_poll_a_stray_byte_made_a_target_never_takes_the_rotor_past_its_limit(
    rig: Rig, model: str
) -> None:
    speeds = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0} if model == "rc2800" else {}
    v = rig(
        model,
        emulator={"az_speed_deg_s": 6.0, **speeds, "start_az_deg": 150.0},
        settings={"az_min_deg": 30.0, "az_max_deg": 330.0},
    )
    v.run_until_state(MotionState.IDLE, 30)
    v.run_for(10)
    t = v.now
    v.garble_writes(b"A\r", b"A5\r")  # the next azimuth poll, one byte more on the line
    v.run_until(lambda h: bool(h.frames("move", since=t)), 5, "the poll taken as a target")
    v.run_for(60)
    assert (
        v.truth().az_deg >= 30.0 - 5.0
    )  # stopped within a few degrees of the limit, if not before
    told = [e.message for e in v.errors(since=t)]
    assert any("no command from the bridge" in m for m in told), told  # and the user told why


def test_an_elevation_poll_a_stray_byte_made_a_target_is_stopped_too(rig: Rig) -> None:
    """``E`` CR read as ``E5`` CR: the elevation turns down from 45 towards 5, past an
    el_min_deg of 20, unless stopped."""
    v = rig(
        "rc2800",
        emulator={
            "az_speed_deg_s": 6.0,
            "el_speed_deg_s": 3.0,
            "start_az_deg": 150.0,
            "start_el_deg": 45.0,
        },
        settings={"el_min_deg": 20.0},
    )
    v.run_until_state(MotionState.IDLE, 30)
    v.run_for(10)
    t = v.now
    v.garble_writes(b"E\r", b"E5\r")
    v.run_until(lambda h: bool(h.frames("move", since=t)), 5, "the poll taken as a target")
    v.run_for(60)
    assert v.truth().el_deg is not None and v.truth().el_deg >= 45.0 - 10.0
    assert abs(v.truth().az_deg - 150.0) < 1.0
    told = [e.message for e in v.errors(since=t)]
    assert any("no command from the bridge" in m for m in told), told
