"""Attack 18: a second bridge whose ``mqtt.base_topic`` is a rotator's topic of a bridge already
running on the broker (``rotor/tower``: bridge A's rotator ``tower``, A having two rotators)
starts without a word of refusal: interfaces/mqtt/claim.py's first look reads only its own
``B/bridge/info`` (``rotor/tower/bridge/info``), where no bridge is. Its one rotator's topics
are then A's tower's: a target for A's tower on ``rotor/tower/target`` turns both rotors, and
the two bridges put their own bearings, states and statuses back over each other's (said only
in their logs, "a second bridge on this base topic?"). Two bridges on one base topic are
refused (test_two_bridges.py); one under the other's rotator is the same clash."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import pytest

from bridge.emulators.pty import EmulatedPort
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


def station_on_rotor(a: Rig) -> EmulatedPort[Any]:
    """Bridge A: base topic ``rotor``, rotators ``tower`` (``rotor/tower``) and ``yagi``."""
    tower = a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
    a.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
    return tower


def station_on_tower(b: Rig, rid: str = "mast") -> EmulatedPort[Any]:
    """Bridge B: base topic ``rotor/tower`` (A's tower's), one rotator: its topics are A's
    tower's."""
    b.base = "rotor/tower"
    return b.add(rid, emu={"start_az_deg": 200, "jitter_deg": 0})


@pytest.mark.parametrize("rid", ["mast", "tower"])  # (c): its rotator named as A's
def test_a_bridge_on_another_live_bridges_rotator_topic_refuses_naming_it_and_leaves_nothing(
    tmp_path: Path, broker: Mosquitto, probe: Probe, rid: str
) -> None:
    """claim.py rule 5, B after A: refused at its first look, naming A and the clashing topic,
    with nothing retained left behind (not even an offline, claim rule 5's (a): the older
    bridge's next start was refused for good by one); A's restart then runs and turns."""
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        tower = station_on_rotor(a)
        first = a.start()
        a.ready("tower")
        a.ready("yagi")
        before = retained_snapshot(broker.port, "rotor/#")
        station_on_tower(b, rid)
        app = b.start()
        wait_until(app.failed.is_set, 15, "the bridge on rotor/tower refuses")
        assert app.failure is not None
        assert first.me.id in app.failure and "'rotor/tower/info'" in app.failure, app.failure
        b.stop()  # as run() does on a refusal
        assert retained_snapshot(broker.port, "rotor/tower/bridge/#") == {}
        after = retained_snapshot(broker.port, "rotor/#")
        changed = {t for t in before.keys() | after.keys() if before.get(t) != after.get(t)}
        assert changed <= {"rotor/tower/status", "rotor/yagi/status"}, changed
        assert not first.failed.is_set()
        a.stop()
        t = probe.caught_up()
        again = a.start()
        a.ready("tower", after=t)
        probe.publish("rotor/tower/target", "90")
        tower.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
        assert not again.failed.is_set()


def test_a_bridge_whose_rotator_topic_is_a_live_bridges_base_topic_refuses(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """claim.py rule 5, A after B: B runs on ``rotor/tower``; A (``rotor``, rotator ``tower``)
    is refused at its first look, naming B's ``rotor/tower/bridge/info``; a target on
    ``rotor/tower/target`` then turns B's rotor alone."""
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        mast = station_on_tower(b)
        other = b.start()
        b.ready("mast")
        tower = station_on_rotor(a)
        app = a.start()
        wait_until(app.failed.is_set, 15, "the bridge on rotor refuses")
        assert app.failure is not None
        assert other.me.id in app.failure and "'rotor/tower/bridge/info'" in app.failure
        a.stop()
        assert retained_snapshot(broker.port, "rotor/bridge/#") == {}
        assert retained_snapshot(broker.port, "rotor/yagi/#") == {}
        probe.publish("rotor/tower/target", "90")
        mast.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
        assert tower.state().az_deg == 0 and not other.failed.is_set()


@pytest.mark.parametrize("first", ["rotor", "rotor/tower"])
def test_a_gone_bridges_leftovers_on_its_topics_refuse_nothing(
    tmp_path: Path,
    broker: Mosquitto,
    probe: Probe,
    first: str,
    caplog: pytest.LogCaptureFixture,
) -> None:
    """claim.py rule 5: the other bridge stopped (its rotators' availability and its bridge
    state ``offline``, its infos left retained): the next bridge runs, and says what it found."""
    caplog.set_level(logging.WARNING)
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        station_on_rotor(a)
        mast = station_on_tower(b)
        gone, then, rid = (a, b, "mast") if first == "rotor" else (b, a, "tower")
        old = gone.start()
        gone.ready("tower" if gone is a else "mast")
        gone.stop()
        probe.wait_value(f"{first}/bridge/state", "offline", 5)
        t = probe.caught_up()
        app = then.start()
        then.ready(rid, after=t)
        assert not app.failed.is_set()
        assert any(old.me.id in r.getMessage() for r in caplog.records), caplog.text
        if then is b:
            probe.publish("rotor/tower/target", "90")
            mast.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)


def test_its_own_restart_before_the_broker_saw_it_die_runs(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """claim.py rule 5: killed outright, the bridge left its rotators' ``online`` and its infos
    (its bridge state too, until the broker notices): its own instance, it runs again."""
    with Rig(tmp_path, broker, probe) as a:
        tower = station_on_rotor(a)
        bridge = a.start_process()
        a.ready("tower", 30)
        bridge.kill()
        t = probe.caught_up()
        again = a.start_process()
        a.ready("tower", 30, after=t)
        probe.publish("rotor/tower/target", "90")
        tower.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
        assert again.alive()


def test_a_bridge_killed_on_the_same_base_topic_is_still_taken_over(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """claim.py rule 5 beside rule 2: killed outright, a bridge with one rotator leaves that
    rotator's ``rotor/availability`` ``online`` beside its ``rotor/info``; its last will on
    ``rotor/bridge/state`` says it is gone, so the next bridge on ``rotor`` takes over, as
    before rule 5, and is not refused for that rotator's leftovers."""
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.mqtt_extra = {"keepalive_s": 5}  # (the broker sends its will 7.5 s after the kill)
        a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
        bridge = a.start_process()
        a.ready("tower", 30)
        bridge.kill()
        probe.wait_value("rotor/bridge/state", "offline", 20)
        assert retained_snapshot(broker.port, "rotor/availability") == {
            "rotor/availability": b"online"
        }
        mast = b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        t = probe.caught_up()
        app = b.start()
        b.ready("mast", after=t)
        probe.publish("rotor/target", "90")
        mast.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
        assert not app.failed.is_set()


def test_the_service_refused_on_a_rotator_topic_exits_with_code_2_naming_the_topic(
    tmp_path: Path, rig: Rig
) -> None:
    """claim.py rule 5 through the CLI: as rule 2's refusal, code 2 (systemd does not restart
    it) and one line naming the other instance and the topic."""
    station_on_rotor(rig)
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
    last = done.stderr.strip().splitlines()[-1]  # (the CLI's own line, after the log's)
    assert last.startswith("rotor-bridge: ") and "'rotor/tower/info'" in last, done.stderr
    assert app.me.id in last and "mqtt.base_topic" in last
    assert retained_snapshot(rig.broker.port, "rotor/tower/bridge/#") == {}
