"""A careless or hostile client on every command topic of the features (bridge/feature.py,
interfaces/mqtt/service.py rules 1 and 2), under MQTT 5 and 3.1.1: real mosquitto, the Rotor-EZ
emulator on a real pty, the bridge in this process, and a toy feature's own topic beside the
registry's (tests/engine/test_feature_commands.py). What a user must see: a retained command on
any of them never moves the rotor, a flood of empty, binary, huge and malformed messages on all
of them moves nothing, and a STOP sent right after the flood stops the turning rotor, whose
bridge then still takes a target.
"""

from __future__ import annotations

import json
import threading
import time

import pytest

import bridge.feature
from bridge.app import App
from bridge.features import FEATURES
from tests.engine.test_feature_commands import TOY
from tests.support.rig import Rig

FEATURE_TOPICS = ("beam", "track", "follow", "control/claim", "control/release", "health/reset")
JUNK = (
    b"",
    b"\x00\xff\xfe",
    b"{",
    b"[]",
    b"null",
    b"NaN",
    b'{"a":' * 2000 + b"1" + b"}" * 2000,
    b"x" * 200_000,
    b"\xef\xbb\xbfON",
    b'"\xc3"',
)


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_retained_and_flooded_feature_topics_move_nothing_and_a_stop_after_them_wins(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, protocol: str
) -> None:
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, TOY))
    emu = rig.add("tower", emu={"start_az_deg": 20, "speed_deg_s": 20})
    retained = {"beam": b"aim 200", "track": b"sun", "control/claim": b"{}"}
    for leaf, payload in retained.items():
        rig.probe.publish(rig.t(leaf), payload, retain=True)
    settings = rig.settings.model_copy(
        update={"mqtt": rig.settings.mqtt.model_copy(update={"protocol": protocol})}
    )
    t0 = time.monotonic()
    rig.app = App(settings)
    rig.app.start()
    rig.ready("tower")
    rig.probe.wait_for(rig.t("error"), lambda m: b"retained" in m.payload, after=t0)
    for leaf in retained:
        rig.probe.publish(rig.t(leaf), b"", retain=True)
    assert not emu.frames("executed", "stored")
    rig.arrived("tower", 20)

    rig.probe.publish(rig.t("target"), "300")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 25)
    for payload in JUNK:
        for leaf in FEATURE_TOPICS:
            rig.probe.publish(rig.t(leaf), payload, qos=0)
    rig.probe.publish(rig.t("stop"), "")
    stopped = emu.wait_for(lambda s: not s.is_moving, 10)
    assert stopped.az_deg < 250, stopped
    t1 = time.monotonic()
    rig.probe.wait_value(rig.t("state"), "idle", timeout_s=20, after=t1)
    assert not emu.state().is_moving

    rig.probe.publish(rig.t("target"), "60")  # the bridge still works
    rig.arrived("tower", 60)
    errors = [json.loads(m.payload) for m in rig.probe.messages if m.topic == rig.t("error")]
    assert errors, "the junk was refused without a word"


def test_a_stop_wins_over_a_controller_flooding_junk_and_half_replies(rig: Rig) -> None:
    """The serial side: while one rotator's controller floods its line with junk and replies
    cut short, a STOP reaches that rotator and one for its neighbour reaches the other."""
    noisy = rig.add("noisy", emu={"start_az_deg": 20, "speed_deg_s": 20})
    quiet = rig.add("quiet", emu={"start_az_deg": 20, "speed_deg_s": 20})
    rig.start()
    rig.ready("noisy")
    rig.ready("quiet")
    for rid, emu in (("noisy", noisy), ("quiet", quiet)):
        rig.probe.publish(rig.t(rid, "target"), "300")
        emu.wait_for(lambda s: s.is_moving and s.az_deg > 25)
    stop_flood = threading.Event()

    def flood() -> None:
        junk = (b"\xe0" * 64, b";1", b";12", b"AI1;\xff", b"\x00" * 32, b";3")
        i = 0
        while not stop_flood.wait(0.005):  # not a deadline: the flood's pace
            noisy.inject(junk[i % len(junk)])
            i += 1

    flooder = threading.Thread(target=flood, daemon=True)
    flooder.start()
    try:
        rig.probe.publish(rig.t("quiet", "stop"), "")
        assert quiet.wait_for(lambda s: not s.is_moving, 10).az_deg < 250
        rig.probe.publish(rig.t("noisy", "stop"), "")
        assert noisy.wait_for(lambda s: not s.is_moving, 10).az_deg < 250
    finally:
        stop_flood.set()
        flooder.join()
    assert noisy.frames("stop") and quiet.frames("stop")
