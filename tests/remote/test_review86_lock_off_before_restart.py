"""Review 86 (interfaces/mqtt/remote.py rule 10, 6887e738): a held lock ON is judged in a new
run of the station's bridge as if nothing had happened in the old run after the remote last
heard it: the stamp counts as 0, and the lock OFF the new run shows from place 0 (kept in the
state file) is read as the lock OFF the lock ON was asked against. But the lock the restart
kept may be a LATER word the remote never saw: its lock ON went into the station's dying
connection, the remote's own link then dropped a while (the operator's Wi-Fi), and in that
while the station came back, someone at the tower locked it and unlocked it again (Home
Assistant, lock OFF: after the remote's lock ON), and the station's bridge restarted (an
update). When the remote is back, its old lock ON goes again and locks the station: the tower's
later lock OFF undone, the operator's next turn stopped and refused.
Real parts: mosquitto, the station's bridge as its own process on an emulated Rotor-EZ behind a
route this test cuts and heals (attack 26's), the remote behind a route of its own, its
console lock and rotctld, Home Assistant's lock words published as it would."""

from __future__ import annotations

import contextlib
import json
from collections.abc import Iterator

import pytest

from bridge.core.errors import Refused
from bridge.core.model import Lock, Source
from bridge.remote.run import Remote
from bridge.remote.settings import RemoteSettings
from tests.remote.test_attack26_stop_into_a_partition import (
    START_AZ,
    CuttableLink,
    killable_station,
    route,  # noqa: F401  (the fixture)
)
from tests.support import wait_until
from tests.support.mosquitto import free_port
from tests.support.mqtt import Message
from tests.support.remote import ask
from tests.support.rig import Rig
from tests.support.waiting import slow

TURN_AZ = 60.0


def station_back(station: Rig, remote: Remote, mark: int) -> None:
    """The station's bridge back as the probe saw it after ``mark``: its first heartbeat
    after it said ``online`` (a clean session: subscribed by then)."""
    bridge_state, beat = remote.station.bridge_state, remote.station.bridge_heartbeat
    online: list[bool] = []

    def beat_after_online(m: Message) -> bool:
        if m.topic == bridge_state and m.payload == b"online":
            online.append(True)
        return bool(online) and m.topic == beat

    station.probe.wait(beat_after_online, slow(30), "the station's bridge back", mark)


def remote_over(remote_route: CuttableLink, port: int) -> Remote:
    """The remote (operator DL1ABC, rotator ``tower`` on rotctld ``port``) reaching the broker
    over ``remote_route``; not yet started."""
    remote = Remote(
        RemoteSettings(
            operator="DL1ABC",
            mqtt={"host": "127.0.0.1", "port": remote_route.port, "base_topic": "rotor"},
            endpoints=[{"rotator": "tower", "rotctld_port": port}],
        )
    )
    return remote


def saved_lock(station: Rig) -> bool | None:
    """The station's state file's lock for ``tower`` (None: not there, or not whole yet)."""
    try:
        entry = json.loads((station.tmp / "state.json").read_text())["rotators"]["tower"]
    except (OSError, ValueError, KeyError):
        return None
    locked = entry.get("locked")
    return locked if isinstance(locked, bool) else None


def run_of(m: Message) -> str:
    return str(json.loads(m.payload)["order"]["run"])


def restarted_and_the_remote_back(
    station: Rig, remote: Remote, remote_route: CuttableLink, first: Message
) -> None:
    """The station's bridge killed and started again, its new run (other than ``first``'s)
    on ``R/status``; then the remote's route healed and the remote reading that new run."""
    status = station.topic("tower", "status")
    mark = station.probe.mark()
    assert station.bridge is not None
    station.bridge.kill()  # the station's bridge restarts ...
    station.start_process()
    new = station.probe.wait(  # ... its new run
        lambda m: m.topic == status and run_of(m) != run_of(first),
        slow(30),
        "the station's new run",
        mark,
    )
    remote_route.heal()  # the remote back, on a new connection
    wait_until(
        lambda: (remote.view.get(status) or b"").find(run_of(new).encode()) >= 0,
        slow(30),
        "the remote reading the new run",
    )


@pytest.fixture
def station(rig: Rig, route: CuttableLink) -> Iterator[Rig]:  # noqa: F811
    yield from killable_station(rig, route, emu={"start_az_deg": START_AZ, "jitter_deg": 0})


@pytest.fixture
def remote_route(rig: Rig) -> Iterator[CuttableLink]:
    link = CuttableLink(rig.broker.port)
    yield link
    link.close()


def test_a_lock_off_at_the_tower_before_a_restart_is_not_undone_by_an_older_lock_on(
    station: Rig,
    route: CuttableLink,  # noqa: F811
    remote_route: CuttableLink,
) -> None:
    port = free_port()
    remote = remote_over(remote_route, port)
    remote.start()
    try:
        emu = station.emus["tower"]
        rotator = remote.rotators[0]
        wait_until(lambda: rotator.away() is None, slow(30), "the station heard")
        lock, lock_state = station.topic("tower", "lock"), station.topic("tower", "lock/state")
        status = station.topic("tower", "status")

        def said() -> bytes | None:  # the station's lock/state, as the broker has it
            last = station.probe.last(lock_state)
            return None if last is None else bytes(last.payload)

        wait_until(lambda: said() == b"OFF", slow(10), "the station's lock/state OFF")
        first = station.probe.last(status)
        assert first is not None
        route.cut()  # the station's route dies; the remote still hears it a while
        with contextlib.suppress(Refused):  # (taken by the broker, or said not delivered)
            rotator.submit(Lock(on=True, source=Source.MQTT), "lock ON")
        remote_route.cut()  # the remote's own link drops a while
        mark = station.probe.mark()
        route.heal()  # the station comes back meanwhile ...
        station_back(station, remote, mark)
        for word in ("ON", "OFF"):  # ... and the tower locks it, and unlocks it: later words
            mark = station.probe.mark()
            station.probe.publish(lock, word)
            station.probe.wait(
                lambda m, w=word: m.topic == lock_state and m.payload == w.encode(),
                slow(30),
                f"the tower's lock {word} taken",
                mark,
            )
        # the station's bridge restarts (an update, well after the lock OFF was saved: killed
        # before, it starts locked, the safe side of runtime/kept.py rule 2, not this remote's)
        wait_until(lambda: saved_lock(station) is False, slow(10), "the lock OFF saved")
        # ... its new run shows the lock OFF the tower left
        restarted_and_the_remote_back(station, remote, remote_route, first)
        wait_until(lambda: rotator.away() is None, slow(30), "the station heard again")
        answer = ask(port, f"P {TURN_AZ:g} 0\n".encode())  # the operator's next turn
        wait_until(
            lambda: (
                said() == b"ON"
                or (not emu.state().is_moving and abs(emu.state().az_deg - TURN_AZ) < 2)
            ),
            slow(30),
            "the station locked again, or the rotor at the operator's target",
        )
    finally:
        remote.stop()
    assert said() == b"OFF", (
        f"the lock OFF at the tower, after the remote's lock ON, undone by that lock ON sent "
        f"again over the station's restart; P {TURN_AZ:g}: {answer!r}"
    )
