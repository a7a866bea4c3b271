"""Review 35 on db50b34f: markers a new connection's look finds refused are asked again every
RESEND_MAX_S (halts.py ``resend_if_due``, ``word.probe()``), with no hold up and no marker of
the stop lane out: the look said them lost before any STOP. Each asking is logged as "a marker
of the stop lane did not come back yet; sending another", every 30 s for as long as the
connection lasts and the ACL denies them: a user reading the log looks for a STOP that was
never sent, and the log says nothing of what it is (the broker asked whether its ACL changed).
"""

from __future__ import annotations

import logging

import pytest

from tests.mqtt.test_attack5_refused_markers import ConfirmedRig


def test_asking_the_broker_again_is_not_said_as_a_stop_lane_s_marker_not_back(
    caplog: pytest.LogCaptureFixture,
) -> None:
    rig = ConfirmedRig()
    svc = rig.svc
    # an earlier connection's resent markers were refused on both topics (0x87); the bridge
    # reconnected under the same ACL, its look's probe refused, its hello never back
    for topic in ("rotor/bridge/fence", "rotor/bridge/hello"):
        rig.delivery.deny(topic, "publish to", "Not authorized")
    svc.main_gone()
    svc.markers_denied()
    with caplog.at_level(logging.INFO, logger="bridge.interfaces.mqtt.halts"):
        rig.run(600, "Not authorized")  # ten minutes, no STOP anywhere
    assert not svc._halts.word.holding  # noqa: SLF001
    said = [r.getMessage() for r in caplog.records if "stop lane" in r.getMessage()]
    assert not said, f"no STOP was sent, and the log says a stop lane's marker is late: {said}"
