"""Review 113's fix (link.py rule 11: an answer torn past any form is garbled) at rest: a
session whose readings were taken, its rotor at rest, then every byte garbled (its line ends
too). Those answers are garbled ones, not first readings (controller.py rule 9: the bearing it
stood at is there to doubt them against): no stop goes to it but the unwatched stop at rest,
said as such (was "no unwatched stop": superseded by review 116, the team's decision that the
limits hold over a rotor the bridge cannot watch, answers torn at rest counted as first
readings' are: a hand turn on such a line ran past ``az_min_deg`` unstopped), and the offline
says the controller answers garbled, not that it stopped answering (rule 2: before
the fix a GS-232B's was 'stopped answering', the user sent to the cable).

In virtual time: the emulated box at rest at 150, read; then every byte it sends reaches the
host XORed with 0x5A.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.test_review113_every_byte_garbled_unwatched import torn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
SETTLE_S = 60  # for the first readings to be taken, at rest (virtual time)
READ_S = 5  # idle polls read at rest (virtual time, not a deadline)
WATCH_S = 60  # ten silence timeouts, the offline and what follows (virtual time)
UNWATCHED = "readings in a row at rest do not agree"


@pytest.mark.parametrize("model", ["gs232b", "easycomm2", "rc2800-az"])
def test_every_byte_garbled_at_rest_is_told_garbled_and_gets_no_other_stop(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"start_az_deg": REST_DEG})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.run_for(READ_S)
    t = v.now
    v.to_host = torn
    v.run_for(WATCH_S)
    said = [e.message for e in v.errors(since=t)]
    unwatched = [s for s in said if UNWATCHED in s]  # (review 116: the rotor is not watched)
    assert not v.frames("stop", since=t) or unwatched, f"a stop to a rotor at rest; said: {said}"
    offline = [s for s in said if "answer" in s]
    assert offline and all("garbled" in s for s in offline), said
    assert not v.status.available
