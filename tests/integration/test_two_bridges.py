"""Two bridges on one base topic (issue 14, item 11; interfaces/mqtt/claim.py): before, they deleted
each other's Home Assistant discovery (0 of 26 configs left) and overwrote each other's state. Real
parts: mosquitto, two bridges (App) each with an emulated controller, and the CLI's exit code."""

from __future__ import annotations

import json
import logging
import socket
import time
from pathlib import Path

import pytest

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces.mqtt.claim import Instance
from tests.support import Probe, free_port, retained_snapshot, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.process import run_cli, to_toml
from tests.support.rig import Rig
from tests.support.waiting import slow

PREFIX = "homeassistant"


def configs(port: int, node: str) -> dict[str, bytes]:
    snap = retained_snapshot(port, f"{PREFIX}/#")
    return {t: p for t, p in snap.items() if f"_r_{node}/" in t and p}


def bridge_topics(port: int) -> dict[str, bytes]:
    return retained_snapshot(port, "rotor/bridge/#")


def test_a_second_bridge_on_a_live_base_topic_refuses_and_changes_nothing(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.add("tower", emu={"start_az_deg": 20, "jitter_deg": 0})
        a.start()
        a.ready("tower")
        assert a.app is not None
        ours = configs(broker.port, "tower")
        assert len(ours) > 10
        before = {**bridge_topics(broker.port), **retained_snapshot(broker.port, "rotor/bearing")}
        assert Instance.parse(before["rotor/bridge/info"]) == a.app.me
        b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})  # the same topics: root rotor
        app = b.start()
        wait_until(app.failed.is_set, 15, "the second bridge refuses")
        assert app.failure is not None and a.app.me.id in app.failure
        b.stop()  # as run() does on a refusal
        assert configs(broker.port, "tower") == ours  # none deleted
        assert configs(broker.port, "mast") == {}  # none published
        after = {**bridge_topics(broker.port), **retained_snapshot(broker.port, "rotor/bearing")}
        assert after == before  # not its bearing, not even its offline
        assert not a.app.failed.is_set()


def test_a_bridge_takes_over_from_one_that_is_gone_and_leaves_its_discovery_alone(
    tmp_path: Path, broker: Mosquitto, probe: Probe, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING)
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.add("tower")
        a.start()
        a.ready("tower")
        theirs = configs(broker.port, "tower")
        a.stop()  # a clean stop: bridge/state offline
        probe.wait_value("rotor/bridge/state", "offline", 5)
        b.add("mast")
        t = time.monotonic()  # before the start: it may publish before this thread runs on
        app = b.start()
        b.ready("mast", after=t)
        wait_until(lambda: configs(broker.port, "mast"), 10, "the new bridge's discovery")
        assert Instance.parse(bridge_topics(broker.port)["rotor/bridge/info"]) == app.me
        assert configs(broker.port, "tower") == theirs  # another installation's: not ours
        assert not app.failed.is_set()
        assert any("taking over base topic" in r.getMessage() for r in caplog.records)
        assert any("left alone" in r.getMessage() for r in caplog.records)


def test_of_two_bridges_that_met_while_running_the_younger_yields(rig: Rig) -> None:
    """Claim rule 4: both passed their first looks at once. Stood in for by an info put there
    by hand: a younger one is put back, an older one makes this bridge go, silently."""
    rig.add("tower")
    app = rig.start()
    rig.ready("tower")
    mine = bridge_topics(rig.broker.port)["rotor/bridge/info"]
    younger = Instance("rotor-other-000001", "elsewhere", 7, app.me.started_unix + 60)
    rig.probe.publish("rotor/bridge/info", younger.info([]), retain=True)
    wait_until(lambda: bridge_topics(rig.broker.port)["rotor/bridge/info"] == mine, 5, "put back")
    assert not app.failed.is_set()
    older = Instance("rotor-other-000002", "elsewhere", 8, app.me.started_unix - 60)
    rig.probe.publish("rotor/bridge/info", older.info([]), retain=True)
    wait_until(app.failed.is_set, 5, "this bridge yields")
    assert app.failure is not None and "rotor-other-000002" in app.failure
    rig.stop()
    left = bridge_topics(rig.broker.port)
    assert Instance.parse(left["rotor/bridge/info"]) == older  # not put back
    assert left["rotor/bridge/state"] == b"online"  # the other's, not overwritten with offline


def test_a_bridge_that_yields_while_running_stops_its_rotors_first(rig: Rig) -> None:
    """An attack pass: one forged info (not retained) made a bridge yield mid-turn, and it
    went for good (code 2), its stop express with it: a STOP after it reached nothing and the
    rotor ran on. Now it stops every rotor before it goes, and exits with code 1 (systemd
    starts it again: its first look then decides on what the broker holds)."""
    emu = rig.add("tower", emu={"start_az_deg": 10})
    app = rig.start()
    rig.ready("tower")
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving, 10)
    older = Instance("rotor-forged-0001", "nowhere", 1, 0.0)
    rig.probe.publish("rotor/bridge/info", older.info([]), retain=False)
    wait_until(app.failed.is_set, 5, "this bridge yields")
    assert app.client.yielded
    rig.stop()
    # the Rotor-EZ's stop, written (the emulator's thread may read it a moment after the bridge
    # is gone: on a loaded CI it had not yet)
    emu.wait_for_frame(b";", timeout_s=10)
    emu.wait_for(lambda s: not s.is_moving, 10)
    assert emu.state().az_deg < 290  # stopped on its way, not at the target


def test_a_yielding_bridge_stops_its_rotors_before_it_closes_a_front_end(rig: Rig) -> None:
    """A review: the stop came only once every front end had closed; a web console takes up to
    10 s to, a TCP client that reads nothing 3 s, and the rotor turned on meanwhile. Now the
    stop is on the wire before the first front end is asked to close (and again after)."""
    port = free_port()
    emu = rig.add("tower", emu={"start_az_deg": 10}, rotctld_port=port)
    app = rig.start()
    rig.ready("tower")
    client = socket.create_connection(("127.0.0.1", port), timeout=slow(5))
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving, 10)
    server = app.rotctld[0]
    stopped_before_close: list[bool] = []
    answers: list[bytes] = []
    close = server.stop

    def watched_close(*args: object, **kwargs: object) -> None:  # (a spy: it closes as ever)
        try:  # (the emulator reads what the bridge wrote a moment later)
            wait_until(lambda: any(f.data == b";" for f in emu.frames()), 2, "the stop")
            stopped_before_close.append(True)
        except AssertionError:
            stopped_before_close.append(False)
        # a review: a client still connected then sent P, and the rotor turned again
        client.sendall(b"P 200.0 0.0\n")
        answers.append(client.recv(100))
        close(*args, **kwargs)  # type: ignore[arg-type]

    server.stop = watched_close  # type: ignore[method-assign]
    older = Instance("rotor-forged-0003", "nowhere", 1, 0.0)
    rig.probe.publish("rotor/bridge/info", older.info([]), retain=False)
    wait_until(app.failed.is_set, 5, "this bridge yields")
    rig.stop()
    client.close()
    assert stopped_before_close == [True]
    assert answers == [b"RPRT -5\n"]  # (offline: the bridge is stopping)
    assert not any(f.data.startswith(b"AP1200") for f in emu.frames())
    emu.wait_for(lambda s: not s.is_moving, 10)
    assert emu.state().az_deg < 290


def test_a_yielding_bridge_turns_no_rotor_between_its_verdict_and_its_stop(rig: Rig) -> None:
    """A review: from the verdict to ``stop`` (the serve loop's wait, up to a second) every
    front end still took targets, and a rotctld ``P`` then turned the rotor: refused now."""
    port = free_port()
    emu = rig.add("tower", emu={"start_az_deg": 10}, rotctld_port=port)
    app = rig.start()
    rig.ready("tower")
    client = socket.create_connection(("127.0.0.1", port), timeout=slow(5))
    older = Instance("rotor-forged-0004", "nowhere", 1, 0.0)
    rig.probe.publish("rotor/bridge/info", older.info([]), retain=False)
    wait_until(app.failed.is_set, 5, "this bridge yields")
    client.sendall(b"P 200.0 0.0\n")  # (before ``stop``: the test has not called it)
    answer = client.recv(100)
    rig.stop()
    client.close()
    assert answer == b"RPRT -5\n"
    assert not any(f.data.startswith(b"AP1") for f in emu.frames())


def test_the_refusing_bridge_exits_with_code_2_naming_the_other(tmp_path: Path, rig: Rig) -> None:
    rig.add("tower")
    app = rig.start()
    rig.ready("tower")
    config = tmp_path / "second.toml"
    emu_link = tmp_path / "no-such-port"
    config.write_text(
        to_toml(
            {
                "mqtt": {"host": "127.0.0.1", "port": rig.broker.port, "client_id": "second"},
                "state_file": str(tmp_path / "second-state.json"),
                "rotators": [{"id": "mast", "model": "rotorez", "port": str(emu_link)}],
            }
        )
    )
    done = run_cli("run", "-c", str(config), timeout_s=30)
    assert done.returncode == 2, done.stderr
    assert app.me.id in done.stderr and "mqtt.base_topic" in done.stderr
    assert json.loads(bridge_topics(rig.broker.port)["rotor/bridge/info"])["instance"] == app.me.id


def test_the_yielding_bridge_process_exits_with_code_1(rig: Rig) -> None:
    """Claim rule 4: the service exits with code 1, which systemd restarts (its unit keeps
    code 2, a configuration error or a refusal at the first look, from a restart)."""
    rig.add("tower")
    bridge = rig.start_process()
    rig.ready("tower", 30)
    older = Instance("rotor-forged-0002", "nowhere", 1, 0.0)
    rig.probe.publish("rotor/bridge/info", older.info([]), retain=False)
    wait_until(lambda: not bridge.alive(), 20, "the bridge process yields")
    assert bridge.proc is not None and bridge.proc.returncode == 1
    assert "rotor-forged-0002" in bridge.log()


def test_a_bridge_refused_at_a_reconnect_stops_its_rotors_and_yields(
    rig: Rig, broker: Mosquitto
) -> None:
    """A review: mid-turn, the broker came back holding another installation's info and
    ``online`` (forged, or a second bridge started during the outage): the reconnect's first
    look refused, and the bridge ended for good (code 2) with no stop. After it ran, such a
    refusal is a yield (claim rule 4): its rotors stopped first, then code 1."""
    emu = rig.add("tower", emu={"start_az_deg": 10})
    app = rig.start()
    rig.ready("tower")
    app.client._client.reconnect_delay_set(3, 3)  # (time to put the other's info there)
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving, 10)
    broker.restart()
    other = Instance("rotor-other-000003", "elsewhere", 9, app.me.started_unix - 60)
    operator = Probe(broker.port, "")
    try:
        operator.publish("rotor/bridge/info", other.info([]), retain=True)
        operator.publish("rotor/bridge/state", "online", retain=True)
        wait_until(app.failed.is_set, 20, "the reconnect's look refuses")
    finally:
        operator.close()
    assert app.client.yielded and app.failure is not None and "rotor-other-000003" in app.failure
    rig.stop()  # the Rotor-EZ's stop, written (read by the emulator's thread: waited for)
    emu.wait_for_frame(b";")
    emu.wait_for(lambda s: not s.is_moving, 10)
    assert emu.state().az_deg < 290


@pytest.mark.parametrize(
    "forged",
    [
        pytest.param(b"[" * 100_000, id="JSON nested past the parser's depth"),
        pytest.param(
            b'{"instance": "x", "started": 1' + b"0" * 400 + b"}", id="a start past a float"
        ),
    ],
)
def test_a_forged_info_no_bridge_writes_is_no_other_bridge_and_the_bridge_runs(
    rig: Rig, forged: bytes
) -> None:
    """An attack pass: a retained ``B/bridge/info`` nested past the JSON parser's depth, or
    with a start time past a float's range, raised (RecursionError, OverflowError) in the
    first look, on paho's thread, at every connect: the look never ended, and every target was
    refused "still checking" for as long as the forged message stayed on the broker, restarts
    included. Junk names no instance (claim.py rule 2): the base topic is the bridge's own."""
    rig.probe.publish("rotor/bridge/info", forged, retain=True)
    rig.probe.publish("rotor/bridge/state", "online", retain=True)
    emu = rig.add("tower", emu={"start_az_deg": 20})
    app = rig.start()
    rig.ready("tower")
    rig.probe.publish("rotor/target", "120")
    rig.arrived("tower", 120)
    assert [f.data for f in emu.frames(*BEARING_OUTCOMES)] == [b"AP1120\r"]
    assert Instance.parse(bridge_topics(rig.broker.port)["rotor/bridge/info"]) == app.me
