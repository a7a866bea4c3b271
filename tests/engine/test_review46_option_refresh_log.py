"""Review 46 (a cold run of ./demo, then its log): ``jam on`` typed once, and from then on the
log said ``rotorez: setting jam sent (b'J')`` at INFO every minute while the rotor rested
(options.py rule 1's refresh of a setting the Rotor-EZ forgets at power-off). Under the
systemd unit that is the journal: one line a minute for each option set on each rotator,
1,440 a day each, for a value nobody changed; docs/controllers.md says it is sent again
"after every reconnect and power-on", not every minute. What a user notices: ``journalctl -u
rotor-bridge -f`` scrolls with a setting sent again and again that they set once."""

from __future__ import annotations

import logging

import pytest

from bridge.core.model import MotionState
from bridge.session.options import OPTIONS_REFRESH_S
from tests.engine.virtual import VirtualRotator


def test_an_option_set_once_is_said_once_in_the_log(caplog: pytest.LogCaptureFixture) -> None:
    with VirtualRotator("rotorez") as v:
        v.run_until_state(MotionState.IDLE, 30)
        v.run_for(6.0)  # the Rotor-EZ's brake delay after its start
        with caplog.at_level(logging.INFO, logger="bridge"):
            v.option("jam", "ON")
            v.run_for(5 * OPTIONS_REFRESH_S + 1.0)
        sent = [r for r in v.frames() if r.data.startswith(b"J")]
        assert len(sent) >= 5  # the refresh itself goes on: the controller forgets at power-off
        said = [r.getMessage() for r in caplog.records if "setting jam sent" in r.getMessage()]
        assert len(said) == 1, said
