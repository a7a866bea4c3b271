"""Review 99: a controller that stops answering mid-turn, its line left noisy, has its turn
stopped seconds later than one whose line goes quiet.

controller.py rule 2: a turn no reading watches any more is stopped when the controller goes
offline, "in case it still hears" (the replies lost on their way back: a broken receive wire,
a dead transmitter in the box, an adapter whose RX pin floats). Silence takes it offline after
``silence_timeout_s`` (3 s); garbled answers keep it online up to GARBLED_SILENCE_FACTOR
timeouts (6 s). link.py rule 11's new paragraph (commit 7ae864e1, ``Link.fed``) counts *any*
byte read since the question that the codec made nothing of as a garbled answer. A receive
line that picks up a stray byte now and then (no line end: the codec only holds it) now
counts as the controller answering: the unwatched turn runs on 3 s more before its stop,
18 degrees more at 6 degrees a second, on the GS-232B, Easycomm II and III, RC2800 and
Prosistel Combi-Track alike (the RT-21, Rotor-EZ and SPID codecs report such a byte as noise
at once: no change for them). Before the commit the same line was silence, and the stop went
at 3.2 s.

In virtual time: 3 s into a turn from 0 to 300 every byte the box sends is lost on its way
back, but one in seven, which comes as a noise byte (0xFE, never a line end). The box still
hears everything. The control: the same with nothing coming back at all.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from tests.engine.virtual import VirtualRotator

START = {"start_az_deg": 0.0}
TARGET_DEG = 300.0
MORE_DEG = 1.0  # how much further than the control the rotor may come to rest
SETTLE_S = 10  # connected, idle polls read (virtual time, not a deadline)
TURN_S = 3  # into the turn when the replies are lost (virtual time, not a deadline)
WATCH_S = 30  # long enough for the offline and its stop, however late (virtual time)
NOISE_EVERY = 7  # one byte in this many of the box's comes back as noise
NOISE = b"\xfe"
STOP_SLACK_S = 0.5  # a moving poll and a reply time


def stop_after_cut(v: VirtualRotator, noisy: bool) -> tuple[float, float, list[str]]:
    """Cut the replies mid-turn (with a noise byte now and then if ``noisy``): how long after
    the cut the turn was told unwatched and stopped, where the rotor came to rest, and the
    errors said."""
    v.run_for(SETTLE_S)
    v.target(TARGET_DEG)
    v.run_for(TURN_S)
    cut = v.now
    count = [0]

    def lost(data: bytes, now: float) -> bytes:
        out = b""
        for _ in data:
            count[0] += 1
            if noisy and count[0] % NOISE_EVERY == 0:
                out += NOISE
        return out

    v.to_host = lost
    v.run_for(WATCH_S)
    said = [(t - cut, e.message) for t, e in v.events if t >= cut]
    stopped = [t for t, why in said if "a stop sent, in case it still hears" in why.lower()]
    return (stopped[0] if stopped else math.inf), v.truth().az_deg, [why for _, why in said]


@pytest.mark.parametrize(
    "model", ["gs232b", "easycomm2", "easycomm3", "rc2800-az", "prosistel-combi"]
)
def test_a_stray_byte_now_and_then_does_not_delay_the_stop_of_an_unwatched_turn(
    rig: Callable[..., VirtualRotator], model: str
) -> None:
    quiet_stop_s, quiet_az, _ = stop_after_cut(rig(model, emulator=START), noisy=False)
    noisy_stop_s, noisy_az, said = stop_after_cut(rig(model, emulator=START), noisy=True)
    assert quiet_stop_s < WATCH_S, "the control: silence stops the unwatched turn"
    assert noisy_stop_s <= quiet_stop_s + STOP_SLACK_S, (noisy_stop_s, quiet_stop_s, said)
    assert noisy_az <= quiet_az + MORE_DEG, (noisy_az, quiet_az, said)
