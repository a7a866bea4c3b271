"""Review 108: the stop express's ``early`` word (express.py rule 11, a6477fe9) is carried out
by the bridge with no test of order at all: ``_heard_only_by_express(..., early=True)`` skips
the vouches and asks only whether one of the bridge's connections read a *halt* of the rotator
since. A target the main connection read after the STOP is no halt, so a STOP published before
that target, read late by the express (before its sync word came back), stops the turn to the
newer target: rule 8's promise (a late frame never stops a newer move) broken by the bridge
itself, on the express's behalf.

Real mosquitto, the bridge in this process, the express in its own, a Rotor-EZ on a real pty.
The express reads the STOP late behind the gate of
tests/integration/test_stop_before_the_express_words_are_back.py (a proxy holding what the
broker sends it), its sync words dropped by an ACL (so every stop it reads is early).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.integration.express_gate import (
    OPEN,
    Gate,
    acl_conf,
    gated_start,
    words_dropped,
)
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until


@pytest.fixture
def broker_conf(tmp_path: Path) -> str:
    return acl_conf(tmp_path, OPEN)


@pytest.mark.xfail(
    strict=True,
    reason="review 108: a target published after a STOP is stopped short when the stop "
    "express reads that STOP late, before its sync word is back (its early word)",
)
def test_an_early_stop_read_late_does_not_stop_a_target_published_after_it(
    tmp_path: Path, broker: Mosquitto
) -> None:
    gate = Gate(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, gate, probe) as rig:
            emu, settings, app = gated_start(
                rig, gate, emu={"start_az_deg": 10, "speed_deg_s": 20.0}
            )
            main_and_lane = {settings.effective_client_id(), lane_client_id(settings)}
            gate.refused |= main_and_lane  # the bridge's connections back after the STOP
            words_dropped(app, broker, tmp_path)
            gate.hold(True)  # the express reads what the broker sends it late
            assert probe.publish("rotor/stop", "STOP")  # 1: a STOP (the rotor is still)
            gate.refused -= main_and_lane
            wait_until(
                lambda: (
                    app.client.subscribed_since is not None
                    and app.lane.subscribed_since is not None
                ),
                15,
                "the bridge's connections back and subscribed",
            )
            assert probe.publish("rotor/target", "100")  # 2: then a target, after the STOP
            emu.wait_for(lambda s: s.is_moving, slow(10))  # the bridge carries it out
            gate.hold(False)  # the express reads the older STOP now (early: no frame)
            still = emu.wait_for(lambda s: not s.is_moving and not s.in_brake_delay, slow(30))
            assert abs(still.az_deg - 100) <= 2, f"stopped at {still.az_deg:.1f}, not at 100"
    finally:
        probe.close()
        gate.close()


def test_an_early_stop_is_carried_out_after_a_target_the_bridge_refused(
    tmp_path: Path, broker: Mosquitto
) -> None:
    """The other side of the same rule: only a move the rotator took orders the early STOP
    before it. A target the judge refused (a keep-out sector) leaves the turn published before
    the STOP under way, and that STOP, read by the express alone, stops it."""
    gate = Gate(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, gate, probe) as rig:
            emu, settings, app = gated_start(
                rig, gate, emu={"start_az_deg": 10, "speed_deg_s": 2.0}, keep_out=[[340, 350]]
            )
            assert probe.publish("rotor/target", "300")  # a long turn (145 s)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            main_and_lane = {settings.effective_client_id(), lane_client_id(settings)}
            gate.refused |= main_and_lane  # the bridge's connections back after the STOP
            words_dropped(app, broker, tmp_path)
            gate.hold(True)  # the express reads what the broker sends it late
            assert probe.publish("rotor/stop", "STOP")  # 1: the operator's STOP
            gate.refused -= main_and_lane
            wait_until(
                lambda: (
                    app.client.subscribed_since is not None
                    and app.lane.subscribed_since is not None
                ),
                15,
                "the bridge's connections back and subscribed",
            )
            mark = probe.mark()
            assert probe.publish("rotor/target", "345")  # 2: a target the judge refuses

            def refused() -> bool:
                return any(m.topic == "rotor/error" for m in probe.messages[mark:])

            wait_until(refused, 10, "the target refused")
            assert emu.wait_for(lambda s: True).is_moving  # (the turn to 300 goes on)
            gate.hold(False)  # the express reads the STOP now (early: no frame)
            emu.wait_for(lambda s: not s.is_moving, slow(10))
    finally:
        probe.close()
        gate.close()
