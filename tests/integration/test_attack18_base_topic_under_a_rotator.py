"""Attack 18: a second bridge whose ``mqtt.base_topic`` is a rotator's topic of a bridge already
running on the broker (``rotor/tower``: bridge A's rotator ``tower``, A having two rotators)
starts without a word of refusal: interfaces/mqtt/claim.py's first look reads only its own
``B/bridge/info`` (``rotor/tower/bridge/info``), where no bridge is. Its one rotator's topics
are then A's tower's: a target for A's tower on ``rotor/tower/target`` turns both rotors, and
the two bridges put their own bearings, states and statuses back over each other's (said only
in their logs, "a second bridge on this base topic?"). Two bridges on one base topic are
refused (test_two_bridges.py); one under the other's rotator is the same clash."""

from __future__ import annotations

import json
import time
from pathlib import Path

from bridge.interfaces.mqtt.claim import Instance
from tests.support import Probe, retained_snapshot, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.process import run_cli, to_toml
from tests.support.rig import Rig


def test_a_bridge_on_another_bridges_rotator_topic_never_turns_on_its_targets(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        tower = a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
        a.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        a.start()
        a.ready("tower")
        b.base = "rotor/tower"  # the second bridge's own topics are A's tower's
        mast = b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        app = b.start()
        if not app.failed.is_set():  # refused at once is the fix; started, its rotator answers
            wait_until(  # (b.ready would read A's tower on the same topics)
                lambda: b.status("mast").available or app.failed.is_set(),
                what="the second bridge's rotator to answer",
            )
        probe.publish("rotor/tower/target", "90")
        tower.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
        after = mast.state()
        assert (after.az_deg, after.is_moving) == (200, False), after


def test_a_bridge_on_a_gone_bridges_rotator_topic_starts_and_turns(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """Claim rule 5: a bridge that is gone (its ``B/bridge/state`` ``offline``) leaves its
    info retained; its rotator topics refuse nobody's start."""
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.add("tower")
        a.add("yagi")
        a.start()
        a.ready("tower")
        a.stop()  # a clean stop: rotor/bridge/state offline, its info left retained
        probe.wait_value("rotor/bridge/state", "offline")
        assert Instance.parse(
            retained_snapshot(broker.port, "rotor/bridge/info")["rotor/bridge/info"]
        )
        b.base = "rotor/tower"
        mast = b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        t = time.monotonic()
        app = b.start()
        b.ready("mast", after=t)
        probe.publish("rotor/tower/target", "90")
        b.arrived("mast", 90)
        assert not app.failed.is_set()
        assert mast.state().az_deg != 200


def test_a_bridge_whose_rotator_topic_is_a_live_bridges_base_topic_refuses(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """Claim rule 5, the other way round: base ``rotor``, rotators ``x`` and ``y`` (``rotor/x``)
    beside a live bridge on ``rotor/x``: refused, nothing of the live one's changed."""
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.base = "rotor/x"
        a.add("far", emu={"start_az_deg": 30, "jitter_deg": 0})
        a.start()
        a.ready("far")
        assert a.app is not None
        before = retained_snapshot(broker.port, "rotor/#")
        b.add("x")
        b.add("y")
        app = b.start()
        wait_until(app.failed.is_set, 15, "the second bridge refuses")
        assert app.failure is not None and a.app.me.id in app.failure
        assert "'rotor/x'" in app.failure and "mqtt.base_topic 'rotor'" in app.failure
        b.stop()
        assert retained_snapshot(broker.port, "rotor/#") == before  # not even its offline
        assert not a.app.failed.is_set()


def test_the_refusing_bridge_exits_with_code_2_and_one_line_naming_both_topics(
    tmp_path: Path, rig: Rig
) -> None:
    rig.add("tower")
    rig.add("yagi")
    app = rig.start()
    rig.ready("tower")
    config = tmp_path / "second.toml"
    config.write_text(
        to_toml(
            {
                "mqtt": {
                    "host": "127.0.0.1",
                    "port": rig.broker.port,
                    "client_id": "second",
                    "base_topic": "rotor/tower",
                },
                "state_file": str(tmp_path / "second-state.json"),
                "rotators": [{"id": "mast", "model": "rotorez", "port": str(tmp_path / "none")}],
            }
        )
    )
    done = run_cli("run", "-c", str(config), timeout_s=30)
    assert done.returncode == 2, done.stderr
    said = [line for line in done.stderr.splitlines() if line.startswith("rotor-bridge:")]
    assert len(said) == 1, done.stderr
    assert app.me.id in said[0] and "mqtt.base_topic 'rotor/tower'" in said[0], said
    assert "base topic 'rotor'" in said[0], said
    assert "rotator or group topic 'rotor/tower'" in said[0], said
    assert not app.failed.is_set()


def test_a_running_bridge_says_so_when_a_younger_bridge_comes_online_in_its_tree(
    rig: Rig, probe: Probe
) -> None:
    """Claim rule 5: one that looks only at its own base topic (a bridge from before rule 5)
    starts on ``rotor/tower`` beside a running bridge (stood in for by its info and state):
    the running one, the older, says it on ``B/bridge/info`` and in the log, and goes on:
    its stops still stop its rotor. Once the other is offline it says so no more."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    rig.add("yagi")
    app = rig.start()
    rig.ready("tower")
    old = Instance("rotor-old-000001", "elsewhere", 7, app.me.started_unix + 60)  # no topics
    probe.publish("rotor/tower/bridge/state", "online", retain=True)
    probe.publish("rotor/tower/bridge/info", old.info([]), retain=True)

    def problems() -> list[str]:
        info = retained_snapshot(rig.broker.port, "rotor/bridge/info")["rotor/bridge/info"]
        return list(json.loads(info)["problems"])

    wait_until(lambda: any("rotor-old-000001" in p for p in problems()), 10, "said on info")
    assert not app.failed.is_set()
    probe.publish("rotor/tower/target", "300")
    emu.wait_for(lambda s: s.is_moving, 10)
    probe.publish("rotor/tower/stop", "")
    emu.wait_for(lambda s: not s.is_moving, 10)
    assert emu.state().az_deg < 290  # stopped on its way
    probe.publish("rotor/tower/bridge/state", "offline", retain=True)
    wait_until(lambda: not any("rotor-old" in p for p in problems()), 10, "said no more")
    assert not app.failed.is_set()


def test_a_running_bridge_yields_to_an_older_one_that_overlaps_it(rig: Rig, probe: Probe) -> None:
    """Claim rule 5 as rule 4: two overlapping bridges that passed their first looks at once
    (stood in for by the older one's info and state): the younger stops its rotor and goes."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    rig.add("yagi")
    app = rig.start()
    rig.ready("tower")
    probe.publish("rotor/tower/target", "300")
    emu.wait_for(lambda s: s.is_moving, 10)
    older = Instance("rotor-older-0001", "elsewhere", 8, app.me.started_unix - 60, ("rotor/tower",))
    probe.publish("rotor/tower/bridge/info", older.info([]), retain=True)
    probe.publish("rotor/tower/bridge/state", "online", retain=True)
    wait_until(app.failed.is_set, 10, "this bridge yields")
    assert app.client.yielded and app.failure is not None and "rotor-older-0001" in app.failure
    rig.stop()
    emu.wait_for_frame(b";")
    emu.wait_for(lambda s: not s.is_moving, 10)
    assert emu.state().az_deg < 290
