"""Review 118 (a regression of review 113's fix): a turn under way when the line starts to
garble every byte, its line ends too, is stopped 3 s later than before, 18 degrees further.

controller.py rule 2: a turn that goes offline is stopped then ("a turn no reading watches
does not go on"), and a garbled answer counts as answering for GARBLED_SILENCE_FACTOR silence
timeouts (6 s at the defaults) where silence counts one (3 s). Such a line's answers were
silence (its codecs wait for a line end): the turn was stopped 3.4 s in. Review 113's
link.py rule 11 counts them garbled now (an answer torn past any form), and the same turn is
stopped only 6.4 s in: 3 s more of a rotor no reading watches, for a line from which not one
reading can come (nothing torn past any form is a controller half heard). Easycomm, GS-232A
and RC2800 lines likewise (6.3-6.4 s, the parent 3.3-3.4 s).

In virtual time: the emulated GS-232B turning from 20 to 300 for TURNING_S; then every byte
it sends reaches the host XORed with 0x5A (review 113's ``torn``).
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.resetting import SETTLE_S, START_DEG, turning_watched
from tests.engine.test_review113_every_byte_garbled_unwatched import torn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
WATCH_S = 30.0  # the silence, the offline and what follows (virtual time)
STEP_S = 0.1  # a step of virtual time to see the first stop: not a deadline


def test_a_turn_whose_line_tears_every_byte_is_stopped_at_the_silence_timeout(rig: Rig) -> None:
    v = rig("gs232b", emulator={"start_az_deg": START_DEG})
    t = turning_watched(v)
    v.to_host = torn
    stop_t = None
    while stop_t is None and v.now < t + WATCH_S:
        v.run_for(STEP_S)
        if v.frames("stop", since=t):
            stop_t = v.now - t
    # (the silence timeout, then one reply time: the question asked then decides, rule 2)
    due_s = v.cfg.silence_timeout_s + v.cfg.spec.reply_timeout_s
    said = [e.message for e in v.errors(since=t)]
    assert stop_t is not None and stop_t <= due_s, (
        f"first stop {stop_t} s after the line went bad (due by {due_s:g} s), the rotor "
        f"then at {v.truth().az_deg:.0f}; said: {said}"
    )


def test_a_line_at_rest_that_tears_every_byte_is_offline_at_the_silence_timeout(rig: Rig) -> None:
    """The same at rest (Medium): offline 6.95 s after the line went bad, not 3.95 s as
    before review 113's fix; still told garbled (review 113's at-rest test)."""
    v = rig("gs232b", emulator={"start_az_deg": START_DEG})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    t = v.now
    v.to_host = torn
    v.run_until(lambda h: not h.status.available, WATCH_S, "offline")
    due_s = v.cfg.silence_timeout_s + v.cfg.spec.reply_timeout_s + v.cfg.idle_poll_interval_s
    said = [e.message for e in v.errors(since=t)]
    assert v.now - t <= due_s, f"offline {v.now - t:.2f} s after the line went bad; said: {said}"
    assert any("garbled" in s for s in said), said
