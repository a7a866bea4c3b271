"""Attack pass (atkn1): a target the rotor is already within tolerance of is logged at INFO
each time (session/targets.py), with no rate limit. Any program that reaches a front end
(rotctld here; PST, N1MM, GS-232, Easycomm alike) writes one line per target: some 800
lines a second were measured from three local senders, past journald's default limit (10,000
in 30 s), which then drops every line of the service, its safety warnings too (the same harm
tcplines.py's CHATTER rule and RareLog were written against)."""

from __future__ import annotations

import logging

import pytest

from tests.integration.test_rotctld_integration import _replies, connect, start
from tests.support.rig import Rig

pytestmark = pytest.mark.hamlib


def test_targets_already_reached_are_not_logged_one_line_each(
    rig: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    port, _ = start(rig, start_az_deg=100)
    burst = 300
    with caplog.at_level(logging.INFO, logger="bridge.session.targets"):
        with connect(port) as sock:
            sock.sendall(b"P 100 0\n" * burst)
            replies = _replies(sock, burst).splitlines()
        assert set(replies) == {b"RPRT 0"}, replies  # every one judged and taken
    lines = [r for r in caplog.records if "already within tolerance" in r.getMessage()]
    assert len(lines) <= 10, f"{len(lines)} log lines for {burst} targets already reached"
