"""Review 103: a connection's first readings that go on disagreeing are asked again at the idle
rate, not the moving rate: a Rot2Prog stays offline, its bearing unread, for 8 s more.

controller.py rule 9 (``_doubts_first``, commit fa9df309) asks a connection's first readings
again at once, DOUBTS_TOLD in a row at most, "then at the moving rate" (``poll``'s ``busy``:
the rotor may be turning). The fourth question is written an idle poll after the third answer
all the same: on a SPID Rot2Prog (``idle_poll_interval_s`` 9.3 s) three garbled first answers
leave the rotator shown offline, with no bearing, and a turn it may be making unread, for 8.4 s
more (the fourth question at 9.3 s, the bearing at 10.2 s) where the moving rate (0.2 s) would
ask at once; on the other models an idle poll of 1 s.

In virtual time: the emulated Rot2Prog at rest at 150; its second and third position frames
reach the host 40 and 80 degrees on (no two agree, no three make a turn a rotor can), the rest
as sent.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import frames_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
OFFSETS = [0.0, 40.0, 80.0]
QUERY = b"W" + bytes(10) + b"\x1f "  # spid.py: the status query
SHOWN_WITHIN_S = 3.0  # three garbled answers (0.47 s each) and a moving poll, with room
WATCH_S = 20.0  # two of the Rot2Prog's idle polls (virtual time)


def test_first_readings_that_go_on_disagreeing_are_asked_again_at_the_moving_rate(
    rig: Rig,
) -> None:
    v = rig("rot2prog", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = frames_off(OFFSETS)
    t = v.now
    v.link_up()
    v.run_for(WATCH_S)
    asked = [round(s.t - t, 2) for s in v.writes if s.data == QUERY]
    shown = [
        round(s_t - t, 2) for s_t, s in v.statuses if s.available and s.bearing_deg is not None
    ]
    assert shown and shown[0] <= SHOWN_WITHIN_S, (
        f"the bearing first shown {shown[:1]} s after the start; queries written at {asked[:6]}"
    )
