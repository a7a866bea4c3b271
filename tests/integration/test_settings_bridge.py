"""A controller setting end to end (a GS-232's speed): real mosquitto, real pyserial on a pty,
the bridge, and the GS-232 emulator as the controller. What a user notices: the bytes the box
received, its speed, the retained state, the refusal of a bad value and of a retained one."""

from __future__ import annotations

import json
import time

from tests.support.rig import Rig


def ready(rig: Rig) -> None:
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)


def test_a_speed_goes_out_as_x2_and_a_bad_one_is_refused_with_nothing_sent(rig: Rig) -> None:
    emu = rig.add("tower", model="gs232b")
    rig.start()
    ready(rig)
    rig.probe.publish("rotor/option/speed", "2")
    emu.wait_for(lambda s: s.speed_level == 2, 10)
    assert [f.data for f in emu.frames("speed")] == [b"X2"]
    rig.probe.wait_value("rotor/option/speed/state", "2")
    assert rig.retained()["rotor/option/speed/state"] == b"2"

    for bad, words in [("9", "'9' is not one of 1, 2, 3, 4"), ("fast", "'fast' is not one of")]:
        t = time.monotonic()
        rig.probe.publish("rotor/option/speed", bad)
        err = json.loads(rig.probe.wait_for("rotor/error", after=t).payload)
        assert words in err["message"] and err["kind"] == "refused", err
    # a command after the refusals went through the same line: nothing of them came before it
    rig.probe.publish("rotor/option/speed", "3")
    emu.wait_for(lambda s: s.speed_level == 3, 10)
    assert [f.data for f in emu.frames("speed")] == [b"X2", b"X3"]
    assert emu.frames("refused") == []
    rig.probe.wait_value("rotor/option/speed/state", "3")


def test_a_retained_speed_is_never_acted_on(rig: Rig) -> None:
    emu = rig.add("tower", model="gs232b")
    rig.start()
    ready(rig)
    t = time.monotonic()
    rig.probe.publish("rotor/option/speed", "1", retain=True)
    err = json.loads(rig.probe.wait_for("rotor/error", after=t).payload)
    assert "retained" in err["message"], err
    rig.probe.publish("rotor/option/speed", "", retain=True)  # (cleared)
    rig.probe.publish("rotor/target", "20")  # a later command goes through: the line is up
    emu.wait_for(lambda s: s.az_deg == 20.0 and not s.is_moving, 20)
    assert emu.frames("speed") == [] and emu.state().speed_level == 4
    rig.probe.publish("rotor/option/speed", "1")  # the same value sent live is acted on
    emu.wait_for(lambda s: s.speed_level == 1, 10)
    assert [f.data for f in emu.frames("speed")] == [b"X1"]
