"""Attack 25: an elevation jammed while the azimuth turns is not called stalled until the
azimuth's whole turn is over, then ``stall_timeout_s`` more: its motor drives against the jam all
that while, and the stall blames the azimuth.

``stall_timeout_s`` (motion.py rule 3: "off target with no movement for stall_timeout_s:
stalled", docs/mqtt.md: "a commanded rotor ... made no progress for stall_timeout_s") is what
stops a motor driving against ice, a caught cable, a bent stop. On an az/el rotor movement of
either axis counts as progress for both (motion.py ``progress_t``): an elevation jammed at 0
from the start of a 180 degree move to 190/45 keeps its motor on while the azimuth turns, 30 s
at a GS-232B's 6 degrees a second, and is stopped 40 s after the target, not 10. The stall then
says "rotor stalled at 190° (no progress for 10 s)" (the azimuth, which arrived) and rotor
health counts the stall at azimuth 190, where nothing holds the rotor.

In virtual time on the emulated GS-232B (its elevation axis jammed: the motor runs, the
position stays), the bridge's default ``stall_timeout_s`` of 10 s.
"""

from __future__ import annotations

from bridge.core.model import ErrorKind, MotionState
from tests.engine.virtual import VirtualRotator

STALL_S = 10.0  # the bridge's default stall_timeout_s
POLL_MARGIN_S = 2.0  # a moving poll or two for the reading that tells it (not a deadline)


def test_an_elevation_jammed_while_the_azimuth_turns_is_stopped_within_the_stall_timeout() -> None:
    v = VirtualRotator("gs232b", emulator={"start_az_deg": 10, "start_el_deg": 0})
    assert v.cfg.motion.stall_timeout_s == STALL_S
    v.run_until_state(MotionState.IDLE, 30)
    v.device._el.jam(v.now)  # type: ignore[attr-defined]  # ice on the elevation: no progress
    t0 = v.now
    v.target(190, 45)
    v.run_until(lambda r: r.state is MotionState.STALLED or r.now - t0 > 60, 90, "a stall")
    v.run_for(POLL_MARGIN_S)  # the stop the stall sends goes out
    frames = v.frames(since=t0)
    stops = [f.time_s - t0 for f in frames if f.data == b"S"]
    # the target, and its one try more where the elevation did not move (controller.py rule
    # 11: "a turn that does not start then is a stall as ever, stall_timeout_s from the try")
    tries = [f.time_s - t0 for f in frames if f.data.startswith(b"W")]
    assert v.truth().el_deg == 0.0  # the elevation never moved
    assert stops, "the jammed elevation was never stopped"
    assert 1 <= len(tries) <= 2, tries
    assert stops[0] <= tries[-1] + STALL_S + POLL_MARGIN_S, (
        f"the elevation made no progress from the target on; its motor was stopped "
        f"{stops[0]:.1f} s after it, {stops[0] - tries[-1]:.1f} s after its last try "
        f"(stall_timeout_s {STALL_S:g}): the azimuth's turn, {v.truth().az_deg:.0f} degrees "
        "reached, counted as the elevation's progress"
    )
    said = v.errors(ErrorKind.STALLED, since=t0)
    assert len(said) == 1 and "elevation 0°" in said[0].message, (
        said
    )  # the jammed axis, its reading
