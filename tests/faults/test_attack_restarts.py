"""Restarts an attack pass tried: the bridge killed right after it said lock ON (it must come
back locked: runtime/kept.py rule 2), and a broker speaking MQTT 3.1.1 that keeps a retained
STOP across its own restart (its replay is no second stop: interfaces/mqtt/lastword.py rule
6). Real parts: mosquitto (or nats-server), the bridge as its own process or in-process,
emulated Rotor-EZs on ptys."""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path
from typing import Any

import paho.mqtt.client as mqtt
import pytest

from bridge.app import App, NotYet
from bridge.core.errors import Refused
from bridge.core.model import Source, Target
from bridge.runtime.rotator import Rotator
from tests.support import Probe, retained_snapshot
from tests.support.brokers import Nats, find_nats
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig
from tests.support.state import kept
from tests.support.waiting import slow, wait_until


def test_a_lock_on_the_bridge_said_is_still_on_after_a_crash_right_after_it(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """kept.py rule 2: ``R/lock/state`` says ON once the state file holds it. It went out
    before the writer had written the lock: a crash or power cut in that window (a few
    milliseconds here, tens on an SD card) restarted the bridge unlocked, although it said ON
    (architecture rule 14). The bridge is SIGKILLed the moment a subscriber sees ON; before the
    mend 4 of 6 rounds came back unlocked, and the target after the restart turned the rotor."""
    state = tmp_path / "state.json"
    with Rig(tmp_path, broker, probe) as rig:
        emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10})
        for round_ in range(3):
            state.write_text(json.dumps({"rotators": {"tower": {"locked": False}}}))
            # the broker's word too (the last round's restart left its ON there): since attack
            # 15 a file's OFF no longer outweighs it (kept.py rule 10), so both say OFF here,
            # as a bridge that saved and said OFF leaves them
            assert probe.publish("rotor/lock/state", "OFF", retain=True)
            t = time.monotonic()
            bridge = rig.start_process()
            probe.wait_value("rotor/lock/state", "OFF", timeout_s=30, after=t)
            probe.wait_value("rotor/availability", "online", timeout_s=30, after=t)
            said_off, said_on = threading.Event(), threading.Event()

            def on_message(  # noqa: ANN001
                client,
                userdata,
                m,
                pid: int = bridge.pid,
                said: threading.Event = said_on,
                off: threading.Event = said_off,
            ) -> None:
                if m.payload == b"OFF":
                    off.set()
                if m.payload == b"ON" and not said.is_set():
                    os.kill(pid, signal.SIGKILL)  # the crash, right after the bridge said ON
                    said.set()

            watcher = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=f"watcher-{round_}")
            watcher.on_message = on_message
            watcher.connect("127.0.0.1", broker.port)
            watcher.subscribe("rotor/lock/state")
            watcher.loop_start()
            try:
                assert said_off.wait(slow(10)), "the retained OFF never came"
                watcher.publish("rotor/lock", "ON", qos=1)
                assert said_on.wait(slow(10)), "the bridge never said lock ON"
            finally:
                watcher.loop_stop()
                watcher.disconnect()
            assert bridge.proc is not None
            bridge.proc.wait(slow(10))
            # (the killed bridge's ON, said as it died, may reach the probe after a clock read
            # and pass for the restarted one's)
            t = probe.caught_up()
            bridge = rig.start_process()
            probe.wait_value("rotor/availability", "online", timeout_s=30, after=t)
            lock = probe.wait_for("rotor/lock/state", after=t, timeout_s=10).payload
            assert lock == b"ON", f"round {round_}: the lock said ON came back {lock!r}"
            t = time.monotonic()
            probe.publish("rotor/target", "100")
            # (this target's refusal, not a line the killed bridge's polls left on the
            # controller's wire, said as junk by the new one: a loaded CI run)
            refused = probe.wait_for(
                "rotor/error", lambda m: b"target" in m.payload, after=t, timeout_s=10
            )
            bridge.terminate()
            assert b"locked" in refused.payload, refused.payload
            assert abs(emu.state().az_deg - 10) < 3, f"round {round_}: a locked rotor turned"


class _KeepingMosquitto(Mosquitto):
    """mosquitto that keeps its retained messages across a restart (persistence on)."""

    def config(self) -> str:
        user = "user root\n" if os.geteuid() == 0 else ""  # (it drops to 'mosquitto' otherwise)
        return (
            f"listener {self.port} {self.host}\npersistence true\n"
            f"persistence_location {self.workdir}/\n{user}allow_anonymous true\n"
        )


@pytest.mark.parametrize("kind", ["mosquitto-3.1.1", "nats"])
def test_a_retained_stop_does_not_stop_the_rotor_again_after_a_broker_restart_on_311(
    kind: str, tmp_path: Path
) -> None:
    """lastword.py rule 6, docs/brokers.md: under MQTT 3.1.1 "a retained stop is carried out
    once per retained message". A retained STOP published while the bridge runs arrives
    without its flag (carried out, as it must be) and was not remembered, so the broker's
    replay after its restart (NATS keeps retained messages in JetStream; mosquitto with
    persistence) was taken for a new one: a rotor turning to a later target was stopped
    mid-turn, short of it."""
    if kind == "nats" and find_nats() is None:
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    broker: _KeepingMosquitto | Nats = (
        Nats(tmp_path / "nats") if kind == "nats" else _KeepingMosquitto(tmp_path / "mosquitto")
    )
    broker.start()
    probe = Probe(broker.port)
    try:
        with Rig(tmp_path, broker, probe) as rig:
            if kind == "mosquitto-3.1.1":
                rig.mqtt_extra = {"protocol": "3.1.1"}
            emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10, "speed_deg_s": 8.0})
            rig.start()
            rig.ready("tower", timeout_s=40)
            t = time.monotonic()
            probe.publish("rotor/stop", "STOP", retain=True)  # a dashboard button set to retain
            probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)  # carried out
            probe.publish("rotor/target", "90")
            emu.wait_for(lambda s: s.is_moving and s.az_deg > 20, 10)  # well on its way
            broker.stop()  # (NATS and mosquitto both keep the retained STOP)
            broker.start()
            assert retained_snapshot(broker.port, "rotor/stop") == {"rotor/stop": b"STOP"}
            emu.wait_for(lambda s: not s.is_moving, 60)
            assert abs(emu.state().az_deg - 90) <= 3, emu.state()
    finally:
        probe.close()
        broker.stop()


def test_a_rotator_removed_after_a_crash_is_not_left_online(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """interfaces/mqtt/stale.py: a rotator removed from the configuration kept its retained
    topics for ever (only its Home Assistant configs were deleted). After a crash (the last
    will covers ``B/bridge/state`` alone) ``R/availability`` stayed ``online`` and ``R/state``
    ``moving``: a dashboard or a remote reading ``rotor/+/availability`` showed a rotator that
    no longer exists as online and turning. The next start deletes what it left."""
    with Rig(tmp_path, broker, probe) as rig:
        rig.add("a")
        rig.add("b")
        rig.add("c", emu={"start_az_deg": 10})
        bridge = rig.start_process()
        probe.wait_value("rotor/c/availability", "online", timeout_s=30)
        probe.publish("rotor/c/target", "200")
        probe.wait_value("rotor/c/state", "moving", timeout_s=10)
        bridge.kill()
        probe.wait_value("rotor/bridge/state", "offline", timeout_s=20)
        left = retained_snapshot(broker.port, "rotor/c/#")
        assert left["rotor/c/availability"] == b"online" and left["rotor/c/state"] == b"moving"
        rig.rotators = [r for r in rig.rotators if r["id"] != "c"]
        t = time.monotonic()
        rig.start_process()
        for topic in left:  # each deleted (an empty retained message), none left
            probe.wait_for(topic, lambda m: m.payload == b"", timeout_s=30, after=t)
        assert retained_snapshot(broker.port, "rotor/c/#") == {}
        probe.wait_value("rotor/a/availability", "online", timeout_s=30, after=t)
        assert retained_snapshot(broker.port, "rotor/a/availability") == {
            "rotor/a/availability": b"online"
        }


def test_the_first_look_leaves_a_nested_bridge_and_a_rotator_named_option_alone(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """review 93, interfaces/mqtt/stale.py: a second bridge on ``rotor/site2`` (one rotator:
    its topics on ``rotor/site2/...``) had its retained bearing, state, status and lock
    deleted by the bridge on ``rotor`` at its first look (``rotor/+/availability`` read
    ``rotor/site2/availability`` as a removed rotator's); and a configured rotator named
    ``option`` lost its retained ``R/lock/state`` at every restart (``rotor/option/+/state``
    read it as an option state of a rotator once on the base topic), for good: the client's
    cache lost it too, and an unchanged lock is not published again."""
    (tmp_path / "other").mkdir()
    (tmp_path / "ours").mkdir()
    with Rig(tmp_path / "other", broker, probe) as other:
        other.base = "rotor/site2"
        other.add("far")
        other.start()
        other.ready("far", timeout_s=40)
        probe.wait_value("rotor/site2/lock/state", "OFF", timeout_s=20)
        theirs = retained_snapshot(broker.port, "rotor/site2/#")
        with Rig(tmp_path / "ours", broker, probe) as rig:
            rig.add("a")
            rig.add("option")
            rig.start()
            rig.ready("option", timeout_s=40)
            probe.wait_value("rotor/option/lock/state", "OFF", timeout_s=20)
            rig.stop()  # a restart: the second first look reads it all retained
            t = probe.caught_up()
            rig.start()
            rig.ready("option", timeout_s=40, after=t)
            probe.wait_value("rotor/bridge/state", "online", timeout_s=20, after=t)
            time.sleep(1.0)  # (the look's deletions are sent as it ends)
            ours = retained_snapshot(broker.port, "rotor/option/lock/state")
            assert ours == {"rotor/option/lock/state": b"OFF"}, "a configured rotator's lock"
            left = retained_snapshot(broker.port, "rotor/site2/#")
            for topic in ("rotor/site2/bearing", "rotor/site2/state", "rotor/site2/lock/state"):
                assert left.get(topic) == theirs[topic], f"another bridge's {topic} deleted"


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_a_lock_on_outlives_a_state_file_that_lost_it(
    tmp_path: Path, broker: Mosquitto, probe: Probe, protocol: str
) -> None:
    """kept.py rule 10: the bridge started on a state file that holds no lock for the rotator
    (the service run by hand, whose default state_file is another; a container recreated
    without its volume; the file deleted) while the broker still holds the ``R/lock/state`` ON
    an earlier run said. The state file alone decided: the bridge came back unlocked, put OFF
    over the retained ON without a word, and a target turned a rotor locked for tower work.
    Then (a review) the start put its cached OFF over that ON for as long as the save of the
    lock took: a switch seen OFF, and a crash then left neither the file nor the broker ON."""
    state = tmp_path / "state.json"
    with Rig(tmp_path, broker, probe) as rig:
        rig.mqtt_extra = {"protocol": protocol}  # (3.1.1: the bridge hears its own messages)
        emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10})
        t = time.monotonic()
        bridge = rig.start_process()
        probe.wait_value("rotor/availability", "online", timeout_s=30, after=t)
        probe.publish("rotor/lock", "ON")
        probe.wait_value("rotor/lock/state", "ON", after=t)
        bridge.terminate()
        state.unlink()  # (another state file: it holds nothing of this rotator)
        t = probe.caught_up()
        rig.start_process()
        probe.wait_value("rotor/availability", "online", timeout_s=30, after=t)
        said = probe.wait_for("rotor/error", lambda m: b"R/lock/state" in m.payload, after=t)
        assert b"state file" in said.payload, said.payload
        wait_until(lambda: kept(state, "tower", "locked") is True, 10, "the lock ON saved")
        assert retained_snapshot(broker.port, "rotor/lock/state") == {"rotor/lock/state": b"ON"}
        shown = [m.text for m in probe.on("rotor/lock/state") if m.t > t]
        assert "OFF" not in shown, f"the lock shown OFF over the broker's ON: {shown}"
        t = time.monotonic()
        probe.publish("rotor/target", "100")
        refused = probe.wait_for("rotor/error", lambda m: b"target" in m.payload, after=t)
        assert b"locked" in refused.payload, refused.payload
        assert abs(emu.state().az_deg - 10) < 3, "a rotor locked before the restart turned"
        t = time.monotonic()
        probe.publish("rotor/lock", "OFF")  # (the lock OFF is said over the broker's ON)
        probe.wait_value("rotor/lock/state", "OFF", after=t)


def test_nothing_turns_a_rotor_whose_lock_is_unknown_before_the_broker_said_it(
    tmp_path: Path, probe: Probe
) -> None:
    """kept.py rule 10: a start on a state file that does not say the rotator's lock learns it
    from the broker's ``R/lock/state`` at the first look, but the serial link, rotctld, the
    loggers and the console ran before: a target sent meanwhile (a tracking program that
    reconnects at once; the broker still down after a power cut, or slower to start than the
    bridge) turned a rotor locked for tower work, until the broker came. Motion is refused
    until the first look has said the lock; what it finds there (nothing here) then decides."""
    late = Mosquitto(tmp_path / "broker")  # (not started yet: the bridge starts without it)
    with Rig(tmp_path, late, probe) as rig:
        emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10})
        app = rig.start()
        rot = app.rotators[0]
        wait_until(lambda: rot.status.available, what="the serial link up")
        with pytest.raises(Refused, match="R/lock/state"):
            rot.submit(Target(100.0, None, Source.ROTCTLD))
        assert abs(emu.state().az_deg - 10) < 3, "a rotor whose lock is not known turned"
        late.start()
        try:
            wait_until(lambda: _accepted(rot, Target(100.0, None, Source.ROTCTLD)), what="free")
            rig.arrived("tower", 100)
        finally:
            rig.stop()
            late.stop()


def _accepted(rot: Rotator, target: Target) -> bool:
    try:
        rot.submit(target)
    except Refused:
        return False
    return True


def test_a_start_that_read_the_state_file_before_an_ending_bridge_saved_a_lock_on_keeps_it(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """state_store.py rule 11, an attack pass: a bridge started while one on the same state
    file was ending (``kill`` and a start by hand) read the file when it was built and took
    the installation's lock only when it started. The lock ON the ending one saved between
    the two was written back OFF by the new one, which ran unlocked: a target turned the
    rotor. Now that start writes nothing and ends (exit code 1, to be started again), and the
    next start comes back locked."""
    with Rig(tmp_path, broker, probe) as rig:
        emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10})
        state = rig.settings.state_file
        state.parent.mkdir(parents=True, exist_ok=True)
        state.write_text(json.dumps({"rotators": {"tower": {"locked": False}}}))
        rig.start()
        rig.ready("tower")
        second = App(rig.settings)  # built (the file read) while the first one runs
        t = time.monotonic()
        probe.publish("rotor/lock", "ON")
        probe.wait_value("rotor/lock/state", "ON", timeout_s=10, after=t)  # saved: kept.py rule 2
        rig.stop()  # the first one ends: the installation's lock is free
        with pytest.raises(NotYet, match="changed since this bridge read it") as ended:
            second.start()
        assert ended.value.exit_code == 1  # systemd starts it again
        assert kept(state, "tower", "locked") is True
        t = probe.caught_up()
        rig.start()  # started again: the file as it is now
        rig.ready("tower", after=t)
        assert "locked" in rig.refused("tower", "100")
        assert kept(state, "tower", "locked") is True
        assert abs(emu.state().az_deg - 10) < 3, "a locked rotor turned"


def test_a_lock_on_taken_while_the_bridge_ends_is_on_the_disk_before_it_lets_go(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """app.py rule 6, a review of state_store.py rule 11: a bridge that is ending takes lock
    words to the last (its connections are closed after the state file's last flush), and the
    save of one that came after that flush was left to the writer: on a slow disk (an SD card
    under load) the bridge let go of the installation's lock, and ended, before it was
    written. The next start read the lock OFF and ran unlocked (as its own process, with 2 s
    an fsync, the file said OFF after the end). Now the end waits for it before it lets go."""
    with Rig(tmp_path, broker, probe) as rig:
        emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10})
        state = rig.settings.state_file
        state.parent.mkdir(parents=True, exist_ok=True)
        state.write_text(json.dumps({"rotators": {"tower": {"locked": False}}}))
        app = rig.start()
        rig.ready("tower")
        rot, store, audit_stop = app.rotators[0], app.store, app.audit.stop
        write = store._write
        disk = threading.Event()  # never set: the slowness of the disk, not a synchronisation

        def slow_disk(*args: Any, **kwargs: Any) -> None:
            disk.wait(0.5)  # not a deadline: an fsync of an SD card under load (under flush's 5 s)
            write(*args, **kwargs)

        def lock_on_now() -> None:  # (the stop's next step after the state file's flush)
            store._write = slow_disk  # type: ignore[method-assign]
            probe.publish("rotor/lock", "ON")
            wait_until(lambda: rot.locked, timeout_s=10)
            audit_stop()

        app.audit.stop = lock_on_now  # type: ignore[method-assign]
        rig.stop()
        assert kept(state, "tower", "locked") is True, "let go before the lock ON was kept"
        t = probe.caught_up()
        rig.start()
        rig.ready("tower", after=t)
        assert "locked" in rig.refused("tower", "100")
        assert abs(emu.state().az_deg - 10) < 3, "a locked rotor turned"
