"""Attack: a bridge started against a broker already holding 10,000 retained messages under and
around its base topic, among them retained commands on its own rotators' topics (targets, lock
OFF, stop, nudge, park, preset, track, claims) and junk on its own bridge topics (hello, fence).
It must finish its start-up, move nothing, and obey a fresh command afterwards."""

from __future__ import annotations

import time

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from tests.faults.conftest import Rig, motion_frames
from tests.support import wait_until

RIDS = ("a", "b")


def commands(root: str) -> dict[str, str]:
    return {
        f"{root}/target": "90",
        f"{root}/target/elevation": "10",
        f"{root}/lock": "OFF",
        f"{root}/stop": "STOP",
        f"{root}/nudge": "+20",
        f"{root}/park": "PARK",
        f"{root}/preset": "EU",
        f"{root}/track": "sun",
        f"{root}/follow": "wsjtx",
        f"{root}/control/claim": '{"operator": "DL1ABC", "minutes": 30}',
        f"{root}/control/release": "x",
        f"{root}/option/jam": "ON",
        f"{root}/health/reset": "RESET",
    }


def flood(port: int, n: int = 10_000) -> dict[str, str]:
    """``n`` retained messages, published and acknowledged before this returns."""
    msgs: dict[str, str] = {}
    for rid in RIDS:
        msgs.update(commands(f"rotor/{rid}"))
    msgs.update(commands("rotor"))  # as if the one rotator's topics (R = B)
    for leaf in ("hello", "fence", "fence/lane", "fence/express", "heartbeat"):
        msgs[f"rotor/bridge/{leaf}"] = "junk"
    i = 0
    while len(msgs) < n:
        k = i % 5
        if k == 0:
            msgs[f"rotor/r{i}/target"] = str(i % 360)
        elif k == 1:
            msgs[f"rotor/a/junk/{i}"] = "123"
        elif k == 2:
            msgs[f"rotor/{i}"] = "45"
        elif k == 3:
            msgs[f"rotorx/{i}/target"] = "270"
        else:
            msgs[f"homeassistant/button/x{i}/stop/config"] = "{}"
        i += 1
    c = paho.Client(CallbackAPIVersion.VERSION2, client_id="flooder")
    c.max_inflight_messages_set(1000)
    c.max_queued_messages_set(0)
    c.connect("127.0.0.1", port)
    c.loop_start()
    try:
        infos = [c.publish(t, p, qos=1, retain=True) for t, p in msgs.items()]
        for info in infos:
            info.wait_for_publish(30)
    finally:
        c.disconnect()
        c.loop_stop()
    return msgs


@pytest.mark.parametrize(
    ("express", "protocol"),
    [(False, "5"), (True, "3.1.1")],  # (the other two pairs passed in the attack pass)
    ids=["lane-5", "express-311"],
)
def test_a_start_among_ten_thousand_retained_messages_finishes_and_moves_nothing(
    rig: Rig, express: bool, protocol: str
) -> None:
    rig.express = express
    rig.mqtt_extra = {"protocol": protocol}
    for rid in RIDS:
        rig.add(rid, "rotorez", emu={"start_az_deg": 200, "jitter_deg": 0})
    flood(rig.broker.port)
    t = time.monotonic()
    rig.start()
    for rid in RIDS:
        rig.ready(rid, timeout_s=60)
    rig.probe.wait_value("rotor/bridge/state", "online", timeout_s=30, after=t)
    print(f"ready after {time.monotonic() - t:.1f} s")
    time.sleep(2.0)  # a few polls more: anything the replay would start has started
    assert rig.app is not None and not rig.app.failed.is_set(), rig.app.failure
    for rid in RIDS:
        assert motion_frames(rig, rid) == 0, rid
        s = rig.emus[rid].state()
        assert not s.is_moving and abs(s.az_deg - 200) <= 2, (rid, s)
        assert rig.status(rid).locked is False
    # and it still obeys: a fresh target turns the rotor, a fresh stop stops it
    rig.probe.publish("rotor/a/target", "250")
    rig.arrived("a", 250, timeout_s=20)
    rig.probe.publish("rotor/b/target", "20")
    wait_until(lambda: rig.emus["b"].state().is_moving, 10, "b turns")
    rig.probe.publish("rotor/b/stop", "STOP")
    wait_until(lambda: not rig.emus["b"].state().is_moving, 5, "b stopped")
    assert rig.emus["b"].state().az_deg > 30


def test_a_restart_among_ten_thousand_leftover_rotators_cleans_up_and_moves_nothing(
    rig: Rig,
) -> None:
    """The base topic was this bridge's (its own info, offline, from the last run) and holds
    the state of 2,000 rotators no longer configured, and retained commands for its own."""
    for rid in RIDS:
        rig.add(rid, "rotorez", emu={"start_az_deg": 200, "jitter_deg": 0})
    rig.start()
    for rid in RIDS:
        rig.ready(rid)
    rig.stop()
    rig.probe.wait_value("rotor/bridge/state", "offline", timeout_s=10)
    msgs: dict[str, str] = {}
    for rid in RIDS:
        msgs.update(commands(f"rotor/{rid}"))
    for i in range(2000):
        for leaf in ("availability", "state", "status", "bearing", "lock/state"):
            msgs[f"rotor/old{i}/{leaf}"] = "online" if leaf == "availability" else "1"
    c = paho.Client(CallbackAPIVersion.VERSION2, client_id="flooder")
    c.max_inflight_messages_set(1000)
    c.connect("127.0.0.1", rig.broker.port)
    c.loop_start()
    for info in [c.publish(t, p, qos=1, retain=True) for t, p in msgs.items()]:
        info.wait_for_publish(30)
    c.disconnect()
    c.loop_stop()
    t = time.monotonic()
    rig.start()
    rig.probe.wait_value("rotor/bridge/state", "online", timeout_s=30, after=t)
    for rid in RIDS:
        rig.ready(rid, timeout_s=60, after=t)
    print(f"ready after {time.monotonic() - t:.1f} s")

    def left() -> list[str]:
        try:
            snap = rig.retained()
        except AssertionError:  # (the broker busy with the deletions: not yet)
            return ["?"]
        return [k for k in snap if k.startswith("rotor/old")]

    # docs/mqtt.md: what a rotator removed from the configuration left retained under B/<id>
    # is deleted at the next start's first look. More deletions than paho's queue takes
    # (delivery.MAX_QUEUED) were marked for a retry that never sends them: ~1000 stayed,
    # rotor/oldN/availability "online" for ever on a dashboard.
    try:
        wait_until(lambda: not left(), 30, "the leftover rotators' state deleted")
    finally:
        print(f"after {time.monotonic() - t:.1f} s: {len(left())} left")
    time.sleep(1.0)
    for rid in RIDS:
        assert motion_frames(rig, rid) == 0, rid
        assert not rig.emus[rid].state().is_moving
    rig.probe.publish("rotor/a/target", "250")
    rig.arrived("a", 250, timeout_s=20)
