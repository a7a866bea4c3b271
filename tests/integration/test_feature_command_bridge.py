"""A feature's own command and status block end to end (bridge/feature.py, session/parts.py
rules 5 and 6): a toy feature registered in the test alone (tests/engine/test_feature_commands.py),
real mosquitto, the Rotor-EZ emulator on a real pty, the bridge in this process. What a user
sees: the feature's topic turns the rotor, its block is in the retained ``R/status``, and under
the lock its command is refused on ``R/error`` while the rotor stays where it is.
"""

from __future__ import annotations

import json
import time

import pytest

import bridge.feature
from bridge.features import FEATURES
from tests.engine.test_feature_commands import TOY
from tests.support.rig import Rig


def test_a_features_own_topic_turns_the_rotor_and_its_block_is_in_r_status(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, TOY))
    rig.add("tower", emu={"start_az_deg": 20})
    rig.start()
    rig.ready("tower")
    t0 = time.monotonic()
    rig.probe.publish(rig.t("beam"), "aim 200")
    rig.arrived("tower", 200)
    status = rig.probe.wait_for(
        rig.t("status"), lambda m: json.loads(m.payload).get("beam", {}).get("aimed") == 1, after=t0
    )
    assert json.loads(status.payload)["beam"] == {"label": None, "aimed": 1}

    rig.probe.publish(rig.t("lock"), "ON")
    rig.probe.wait_value(rig.t("lock/state"), "ON", after=t0)
    assert rig.refused("tower", "aim 20", leaf="beam") == (
        "rotator is locked (safety lock ON): motion refused"
    )
    rig.arrived("tower", 200)  # where it was
